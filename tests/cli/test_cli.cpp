// The subd2nurbs executable end to end: exit codes, what goes to stdout and stderr.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <regex>
#include <string>

#include "common/gltf_writer.h"
#include "common/run_command.h"
#include "converter/pipeline/conversion.h"
#include "core/refine/refiner.h"
#include "io/obj_reader.h"
#include "io/temp_dir.h"

using namespace subd2nurbs;
using subd2nurbs::testing::read_text;
using subd2nurbs::testing::TempDir;

namespace {

using Result = subd2nurbs::testing::CommandResult;
using subd2nurbs::testing::quote;

/// Runs subd2nurbs with the given (already quoted) arguments.
Result run(const std::string& args) { return subd2nurbs::testing::run_command(quote(SUBD2NURBS_EXE) + " " + args); }

std::string sample() { return std::string(SUBD2NURBS_SAMPLES_DIR) + "/rounded_box.obj"; }
std::string data(const std::string& name) {
  return std::string(SUBD2NURBS_TEST_DATA_DIR) + "/" + name;
}

/// Python's verdict on a JSON file: 0 if json.load reads it and `condition` (a Python
/// expression over the parsed value `r`) holds, else non-zero.
int python_json_check(const std::string& file, const std::string& condition = "True") {
  const std::string script = "import json,sys; r=json.load(open(sys.argv[1])); sys.exit(0 if (" +
                             condition + ") else 1)";
  const int status = std::system(("/usr/bin/python3 -c " + quote(script) + " " + quote(file)).c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

bool starts_with_file(const std::string& file, const std::string& prefix) {
  return read_text(file).rfind(prefix, 0) == 0;
}

/// Minimal JSON check: brackets balance outside strings, and strings are terminated.
bool json_brackets_balance(const std::string& s) {
  std::string stack;
  bool in_string = false;
  for (size_t i = 0; i < s.size(); ++i) {
    const char c = s[i];
    if (in_string) {
      if (c == '\\') ++i;
      else if (c == '"') in_string = false;
      continue;
    }
    if (c == '"') in_string = true;
    else if (c == '{' || c == '[') stack += c;
    else if (c == '}' || c == ']') {
      if (stack.empty() || stack.back() != (c == '}' ? '{' : '[')) return false;
      stack.pop_back();
    }
  }
  return !in_string && stack.empty();
}

/// The integer value of a top-level "key": N pair, or -1.
long json_int(const std::string& json, const std::string& key) {
  std::smatch m;
  if (!std::regex_search(json, m, std::regex("\n  \"" + key + "\": (-?[0-9]+)"))) return -1;
  return std::stol(m[1]);
}

// --- polar structures -------------------------------------------------------------------------

std::string polar_sample() { return std::string(SUBD2NURBS_SAMPLES_DIR) + "/capped_cylinder.obj"; }

TEST(CliPolar, InfoListsPolarStructuresAndWhyOthersAreNot) {
  const Result r = run("info " + quote(polar_sample()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("2 polar structures: vertex 0 (valence 16), vertex 129 (valence 16)"), std::string::npos) << r.out;
  // OpenSubdiv's pole shapes have one quad ring only: not polar structures, and info says why.
  for (const char* shape : {"corpus/catmark_pole8.obj", "corpus/catmark_pole64.obj"}) {
    const Result p = run("info " + quote(data(shape)));
    ASSERT_EQ(p.exit_code, 0) << p.err;
    EXPECT_NE(p.out.find("0 polar structures"), std::string::npos) << p.out;
    EXPECT_NE(p.out.find("not polar: vertex 4"), std::string::npos) << p.out;
    EXPECT_NE(p.out.find("no 2-layer (only one quad ring)"), std::string::npos) << p.out;
  }
  TempDir dir;
  const Result j = run("info --json " + quote(polar_sample()));
  ASSERT_EQ(j.exit_code, 0);
  std::ofstream(dir.file("i.json")) << j.out;
  EXPECT_EQ(python_json_check(dir.file("i.json"),
                              "[p['valence'] for p in r['polar_structures']] == [16, 16] and r['not_polar'] == []"),
            0);
}

TEST(CliPolar, RefineUsesBpAtPolesUnlessOff) {
  TempDir dir;
  ASSERT_EQ(run("refine " + quote(polar_sample()) + " -l 2 -o " + quote(dir.file("on.obj"))).exit_code, 0);
  ASSERT_EQ(run("refine " + quote(polar_sample()) + " -l 2 --polar off -o " + quote(dir.file("off.obj"))).exit_code, 0);
  const LoadedCage on = read_obj(dir.file("on.obj")), off = read_obj(dir.file("off.obj"));
  auto triangles = [](const LoadedCage& c) {
    int t = 0;
    for (int s : c.input.face_sizes) t += s == 3;
    return t;
  };
  EXPECT_EQ(triangles(on), 2 * 16 * 4);  // each pole keeps a fan of n 2^k triangles
  EXPECT_EQ(triangles(off), 0);          // Catmull-Clark: quads only
  EXPECT_EQ(run("refine " + quote(polar_sample()) + " -l 1 --polar maybe -o " + quote(dir.file("x.obj"))).exit_code, 1);
}

TEST(CliPolar, ConvertMakesCapsUnlessOffAndChecksItsOptions) {
  TempDir dir;
  const std::string in = quote(polar_sample());
  const Result on = run("convert " + in + " -o " + quote(dir.file("on.step")) + " --faces per-quad --report " +
                        quote(dir.file("on.json")));
  ASSERT_EQ(on.exit_code, 0) << on.err;
  EXPECT_EQ(python_json_check(dir.file("on.json"),
                              "r['patches']['polar_caps'] == 2 and r['brep']['faces'] == 16 * 5 + 2 and "
                              "r['brep']['type'] == 'solid' and len(r['polar']['caps']) == 2 and "
                              "all(0 < c['pole_curvature']['max_abs_k'][1] <= 2 * c['pole_curvature']['max_abs_k'][0] "
                              "for c in r['polar']['caps'])"),
            0);
  const Result off = run("convert " + in + " --polar off -o " + quote(dir.file("off.step")) + " --report " +
                         quote(dir.file("off.json")));
  ASSERT_EQ(off.exit_code, 0) << off.err;
  EXPECT_EQ(python_json_check(dir.file("off.json"), "r['patches']['polar_caps'] == 0 and r['polar']['enabled'] == False"), 0);
  const Result two = run("convert " + in + " --radial-steps 2 --lambda 0.9 -o " + quote(dir.file("two.brep")) +
                         " --report " + quote(dir.file("two.json")));
  ASSERT_EQ(two.exit_code, 0) << two.err;
  EXPECT_EQ(python_json_check(dir.file("two.json"), "r['polar']['radial_steps'] == 2 and r['polar']['lambda'] == 0.9"), 0);
  // Packed (the default): the cylinder's regular quads become fewer faces, still one valid solid.
  EXPECT_EQ(python_json_check(dir.file("two.json"),
                              "r['faces']['mode'] == 'packed' and r['faces']['packed'] > 0 and "
                              "r['brep']['faces'] == r['faces']['total'] < 16 * 5 + 2 and "
                              "r['brep']['type'] == 'solid' and r['brep']['valid']"),
            0);
  for (const char* bad : {"--radial-steps 3", "--radial-steps 0", "--lambda 0", "--lambda -1", "--polar yes",
                          "--polar off --separate-poles"}) {
    const Result r = run("convert " + in + " " + bad + " -o " + quote(dir.file("bad.step")));
    EXPECT_EQ(r.exit_code, 1) << bad;
  }
  EXPECT_FALSE(std::ifstream(dir.file("bad.step")).good());
}

}  // namespace

TEST(Cli, InfoOnSample) {
  const Result r = run("info " + quote(sample()));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("vertices     26"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("faces        24"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("8 semi-sharp edges"), std::string::npos) << r.out;
  EXPECT_TRUE(r.err.empty()) << r.err;
}

TEST(Cli, InfoJsonIsWellFormedAndMatchesTheMesh) {
  for (const std::string& file : {sample(), data("valid/all_tags.obj"), data("valid/unused_vertex.obj")}) {
    const Result r = run("info --json " + quote(file));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_TRUE(json_brackets_balance(r.out)) << r.out;
    EXPECT_EQ(r.out.front(), '{');
    for (const char* key : {"file", "vertices", "faces", "edges", "corners", "face_sizes",
                            "valences", "boundary", "creases", "holes", "extraordinary_vertices",
                            "unused_vertices", "components", "euler_characteristic", "closed",
                            "bounds", "options", "warnings"})
      EXPECT_NE(r.out.find("\"" + std::string(key) + "\":"), std::string::npos) << key;
    const SubdivLevel level = SubdivLevel::from_input(read_obj(file).input);
    EXPECT_EQ(json_int(r.out, "vertices"), level.mesh.num_vertices()) << file;
    EXPECT_EQ(json_int(r.out, "faces"), level.mesh.num_faces()) << file;
    EXPECT_EQ(json_int(r.out, "edges"), level.mesh.num_edges()) << file;
    EXPECT_EQ(json_int(r.out, "corners"), level.mesh.num_corners()) << file;
  }
}

TEST(Cli, InfoReportsWarningsWithLines) {
  const std::string file = data("valid/unused_vertex.obj");
  const Result text = run("info " + quote(file));
  EXPECT_EQ(text.exit_code, 0);
  EXPECT_NE(text.out.find(file + ":6: warning: vertex 5 is not used"), std::string::npos) << text.out;
  const Result json = run("info --json " + quote(file));
  EXPECT_NE(json.out.find(":6: warning: vertex 5 is not used"), std::string::npos) << json.out;
}

TEST(Cli, RefineWritesTheRefinedMesh) {
  TempDir dir;
  const std::string out = dir.file("box_l2.obj");
  const Result r = run("refine " + quote(sample()) + " -l 2 -o " + quote(out));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;  // small mesh: no progress messages
  const LoadedCage cage = read_obj(out);
  EXPECT_EQ(cage.input.num_faces(), 24 * 16);
  EXPECT_EQ(cage.input.num_vertices(), 386);  // V - E + F = 2 with E = 2F
  EXPECT_NO_THROW(validate_cage(cage));
}

TEST(Cli, RefineReportsProgressOnStderrForBigMeshes) {
  TempDir dir;
  const std::string out = dir.file("box_l7.obj");
  const Result r = run("refine " + quote(sample()) + " -l 7 -o " + quote(out));  // 393216 faces
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("refining"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("level 7"), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
  EXPECT_EQ(read_obj(out).input.num_faces(), 24 << 14);
}

TEST(Cli, RefineLevelZeroAndDefault) {
  TempDir dir;
  ASSERT_EQ(run("refine " + quote(sample()) + " -l 0 -o " + quote(dir.file("l0.obj"))).exit_code, 0);
  EXPECT_EQ(read_obj(dir.file("l0.obj")).input.num_faces(), 24);
  ASSERT_EQ(run("refine " + quote(sample()) + " --output " + quote(dir.file("l1.obj"))).exit_code, 0);
  EXPECT_EQ(read_obj(dir.file("l1.obj")).input.num_faces(), 96);  // default: 1 level
}

TEST(Cli, UsageErrorsExitWith1) {
  TempDir dir;
  const std::string out = quote(dir.file("o.obj"));
  EXPECT_EQ(run("").exit_code, 1);                                     // no subcommand
  EXPECT_EQ(run("frobnicate").exit_code, 1);                           // unknown subcommand
  EXPECT_EQ(run("refine " + quote(sample())).exit_code, 1);            // missing -o
  EXPECT_EQ(run("refine " + quote(sample()) + " -l -1 -o " + out).exit_code, 1);
  EXPECT_EQ(run("refine " + quote(sample()) + " -l two -o " + out).exit_code, 1);
  EXPECT_EQ(run("info").exit_code, 1);                                 // missing MESH
  EXPECT_EQ(run("info --bogus " + quote(sample())).exit_code, 1);
  const Result too_deep = run("refine " + quote(sample()) + " -l 20 -o " + out);
  EXPECT_EQ(too_deep.exit_code, 1);
  EXPECT_NE(too_deep.err.find("fewer levels"), std::string::npos) << too_deep.err;
  EXPECT_TRUE(dir.entries().empty());
}

TEST(Cli, InvalidInputExitsWith2AndNamesFileAndLine) {
  const std::string bad = data("invalid/nonmanifold_edge.obj");
  for (const std::string& command : {"info " + quote(bad), "info --json " + quote(bad)}) {
    const Result r = run(command);
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find(bad + ":12: error: non-manifold edge"), std::string::npos) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
  }
  TempDir dir;
  const Result refine = run("refine " + quote(data("invalid/malformed_tag.obj")) + " -o " +
                            quote(dir.file("o.obj")));
  EXPECT_EQ(refine.exit_code, 2);
  EXPECT_NE(refine.err.find("malformed_tag.obj:7: error:"), std::string::npos) << refine.err;
  EXPECT_TRUE(dir.entries().empty());

  const Result missing = run("info " + quote(dir.file("absent.obj")));
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find("absent.obj: error: no such file"), std::string::npos) << missing.err;
}

TEST(Cli, WriteFailureExitsWith3) {
  TempDir dir;
  const std::string out = dir.file("no/such/dir/out.obj");
  const Result r = run("refine " + quote(sample()) + " -o " + quote(out));
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find(out), std::string::npos) << r.err;
  EXPECT_TRUE(dir.entries().empty());
}

TEST(Cli, HelpListsExitCodesAndVersionPrints) {
  const Result help = run("--help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("Exit codes:"), std::string::npos) << help.out;
  EXPECT_NE(help.out.find("3  the output file could not be written"), std::string::npos);
  EXPECT_NE(help.out.find("info"), std::string::npos);
  EXPECT_NE(help.out.find("refine"), std::string::npos);
  EXPECT_NE(help.out.find("convert"), std::string::npos);
  const Result convert_help = run("convert --help");
  EXPECT_EQ(convert_help.exit_code, 0);
  for (const char* option : {"--output", "--level", "--tolerance", "--absolute", "--schema", "--report", "--quiet"})
    EXPECT_NE(convert_help.out.find(option), std::string::npos) << option << "\n" << convert_help.out;
  const Result version = run("--version");
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_EQ(version.out.rfind("subd2nurbs ", 0), 0u) << version.out;
}

// Every subcommand that reads a cage reads glTF too (load_input), and its help says so; check
// and limit measure a .glb like the OBJ it was written from. Oracle: the OBJ's own output.
TEST(CliGltf, EveryCageReadingCommandTakesGltfAndSaysSo) {
  for (const char* command : {"info", "refine", "convert", "check", "limit", "fair"}) {
    const Result help = run(std::string(command) + " --help");
    EXPECT_EQ(help.exit_code, 0) << command;
    EXPECT_NE(help.out.find("glTF / GLB"), std::string::npos) << command << "\n" << help.out;
  }
  TempDir dir;
  const std::string glb = dir.file("box.glb");
  subd2nurbs::testing::GltfOptions o;
  subd2nurbs::testing::write_gltf(read_obj(sample()).input, glb, o);
  const Result from_glb = run("check " + quote(glb) + " --samples 3 --json " + quote(dir.file("g.json")) + " -q");
  ASSERT_EQ(from_glb.exit_code, 0) << from_glb.err;
  const Result from_obj = run("check " + quote(sample()) + " --samples 3 --json " + quote(dir.file("o.json")) + " -q");
  ASSERT_EQ(from_obj.exit_code, 0) << from_obj.err;
  // The same edges and classes; measured values equal up to rounding (the glTF cage's vertices
  // and faces come in another order, so sums run in another order).
  EXPECT_EQ(python_json_check(dir.file("g.json"),
                              "(lambda a, b: all((abs(a[k] - b[k]) <= 1e-9 * max(1.0, abs(b[k]))) if "
                              "isinstance(b[k], float) else a[k] == b[k] for k in b) and a.keys() == b.keys())"
                              "(r['quality']['edges_summary'], json.load(open(\"" +
                                  dir.file("o.json") + "\"))['quality']['edges_summary'])"),
            0);
}

// Each setting's rule is the converter's (pipeline::validate, polar_mode, step_schema, ...): the
// command line prints the rule the pipeline gives for the same value, after its own option name.
// Oracle: the pipeline's SettingsError, called directly.
TEST(Cli, SettingsRulesAreTheConverters) {
  namespace pl = subd2nurbs::pipeline;
  auto settings_rule = [](const std::function<void(pl::ConversionSettings&)>& change) {
    return [change] {
      pl::ConversionSettings s;
      change(s);
      pl::validate(s);
    };
  };
  auto fairing_rule = [](int levels, double membrane) {
    return [levels, membrane] {
      subd2nurbs::EnergyOptions energy;
      energy.levels = levels;
      energy.membrane = membrane;
      pl::validate_fairing(1.0, energy);
    };
  };
  TempDir dir;
  struct Case {
    std::string command, options, flag;
    std::function<void()> converter;  // throws the pipeline's SettingsError for the same value
  };
  const std::string glb = quote(dir.file("p.glb"));
  const std::vector<Case> cases = {
      {"convert", "--polar maybe", "--polar", [] { pl::polar_mode("maybe"); }},
      {"refine", "--polar maybe", "--polar", [] { pl::polar_mode("maybe"); }},
      {"convert", "--schema ap999", "--schema", [] { pl::step_schema("ap999"); }},
      {"convert", "--fit exact", "--fit", [] { pl::fit_mode("exact"); }},
      {"convert", "--faces all", "--faces", [] { pl::face_mode("all"); }},
      {"check", "--faces all", "--faces", [] { pl::face_mode("all"); }},
      {"convert", "--preview " + glb + " --color rainbow", "--color", [] { pl::preview_color("rainbow"); }},
      {"convert", "--level 13", "--level", settings_rule([](pl::ConversionSettings& s) { s.level = 13; })},
      {"check", "--level 13", "--level", settings_rule([](pl::ConversionSettings& s) { s.level = 13; })},
      {"convert", "--radial-steps 3", "--radial-steps",
       settings_rule([](pl::ConversionSettings& s) { s.patch.cap.radial_steps = 3; })},
      {"convert", "--lambda 0", "--lambda", settings_rule([](pl::ConversionSettings& s) { s.patch.cap.lambda = 0; })},
      {"convert", "--fit interpolate --fair=-1", "--fair", settings_rule([](pl::ConversionSettings& s) {
         s.fit.mode = pl::FitMode::Interpolate;
         s.fit.fair_weight = -1;
       })},
      {"fair", "--keep nothing", "--keep", [] { pl::keep_set({"nothing"}); }},
      {"fair", "--levels 5", "--levels", fairing_rule(5, 0)},
      {"fair", "--membrane=-1", "--membrane", fairing_rule(2, -1)},
  };
  for (const Case& c : cases) {
    std::string rule = "(no SettingsError)";
    try {
      c.converter();
    } catch (const pl::SettingsError& e) {
      rule = e.rule();
    }
    const std::string output =
        c.command == "check" ? "" : " -o " + quote(dir.file(c.command == "convert" ? "a.step" : "a.obj"));
    const Result r = run(c.command + " " + quote(sample()) + output + " " + c.options);
    EXPECT_EQ(r.exit_code, 1) << c.command << " " << c.options;
    EXPECT_EQ(r.err, "subd2nurbs: error: " + c.flag + " " + rule + "\n") << c.command << " " << c.options;
  }
  EXPECT_TRUE(dir.entries().empty());  // refused before any output
}

// --- convert ---------------------------------------------------------------------------------

TEST(CliConvert, WritesEveryFormatAndAReportThatParses) {
  struct Case {
    const char* name;
    const char* prefix;  // what the file starts with (IGES: checked by its column layout)
  };
  for (const Case& c : {Case{"box.step", "ISO-10303-21;"}, Case{"box.stp", "ISO-10303-21;"},
                        Case{"box.brep", "DBRep_DrawableShape\n\nCASCADE Topology V"}, Case{"box.iges", ""},
                        Case{"box.igs", ""}, Case{"box.json", "{\"format\":\"subd2nurbs-patches\""}}) {
    TempDir dir;
    const std::string out = dir.file(c.name), report = dir.file("report.json");
    const Result r = run("convert " + quote(sample()) + " -o " + quote(out) + " --report " + quote(report));
    ASSERT_EQ(r.exit_code, 0) << c.name << "\n" << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
    ASSERT_TRUE(std::filesystem::exists(out)) << c.name;
    EXPECT_GT(std::filesystem::file_size(out), 1000u) << c.name;
    EXPECT_TRUE(starts_with_file(out, c.prefix)) << c.name << ": " << read_text(out).substr(0, 80);
    if (std::string(c.name).find(".ig") != std::string::npos) {  // IGES: 80-column start section
      const std::string text = read_text(out);
      ASSERT_GT(text.size(), 80u);
      EXPECT_EQ(text[72], 'S') << text.substr(0, 81);
      EXPECT_EQ(text[80], '\n') << text.substr(0, 81);
    }
    EXPECT_EQ(dir.entries().size(), 2u) << c.name;  // no temporary file left
    EXPECT_EQ(python_json_check(report), 0) << read_text(report);
    // Stage lines and the summary, since --quiet is not given.
    EXPECT_NE(r.err.find("subd2nurbs: building patches..."), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("subd2nurbs: wrote " + out), std::string::npos) << r.err;
  }
}

TEST(CliConvert, ReportDescribesTheSample) {
  TempDir dir;
  const std::string out = dir.file("box.step"), report = dir.file("r.json");
  const Result r = run("convert " + quote(sample()) + " -o " + quote(out) + " --report " + quote(report) + " -q");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;  // --quiet, and the sample gives no warning
  // rounded_box: 24 quads, 26 vertices (8 of valence 3), closed.
  const char* conditions[] = {
      "r['format'] == 'subd2nurbs-report' and r['version'] == 1",
      "r['input'].endswith('rounded_box.obj') and r['output_format'] == 'STEP' and r['step_schema'] == 'AP214'",
      // The default tolerance, 1e-4 of the model size: the valence-3 fans start at 1.7e-3 and
      // fall about 6x per level (docs/patches.md), so each needs 2 extra levels: 0 + 2 + 2.
      "r['coarse_level'] == 0 and r['level'] == 4 and r['extra_levels'] == 0",
      "(lambda t: t['default'] and t['met'] and t['requested'] == 1e-4 and t['fans_deepened'] == 8)(r['deviation']['tolerance'])",
      "{k: r['patches'][k] for k in ('total', 'regular', 'pccm', 'polar_caps')} == {'total': 24, 'regular': 0, 'pccm': 24, 'polar_caps': 0}",
      "r['patches']['poles'] >= 24 * 16 and r['patches']['pieces'] >= 24",
      "r['fans']['smooth'] == 8 and r['fans']['approximate'] == 0 and r['fans']['approximate_fans'] == []",
      // One face per side of the box (its 2 x 2 quads, each at a valence-3 corner, join across
      // the side's C2 edges; the fan rays along the box's edges stay edges): a box's topology.
      "r['brep'] == {'faces': 6, 'edges': 12, 'vertices': 8, 'type': 'solid', 'solids': 1, 'shells': 1, 'valid': True, 'tolerance': r['brep']['tolerance'], 'planar_faces': 0, 'merged_patches': 0, 'folded_planar_patches': 0, 'rejected_planar_faces': 0, 'split_planar_sets': 0}",
      "r['continuity']['max_gap'] < 1e-12 and r['continuity']['max_normal_angle_deg'] < 1e-6",
      "abs(r['continuity']['max_gap_relative'] * r['model_size'] - r['continuity']['max_gap']) <= 1e-15 * r['model_size']",
      "0 < r['deviation']['mean'] < r['deviation']['max'] < 0.01 * r['model_size']",
      "r['deviation']['worst_fan']['valence'] == 3 and r['deviation']['samples'] > 0",
      "r['deviation']['sample_levels'] == 2 and len(r['deviation']['fans']) == 8",
      "sorted(r['timings_ms']) == sorted(['load', 'fit', 'patches', 'packing', 'intersections', 'continuity', 'deviation', 'brep', 'write', 'threads'])",
      "r['timings_ms']['threads'] == __import__('os').cpu_count()",  // one per hardware thread by default
      // One convex-ish closed part: nothing crosses (OCCT's checker agrees: tests/occt).
      "(lambda x: x['components'] == 1 and x['crossing_face_pairs'] == 0 and x['overlap_face_pairs'] == 0 and x['self'] == [] and x['overlaps'] == [] and x['triangles'] > 0)(r['self_intersection'])",
      "r['faces'] == {'mode': 'packed', 'total': 6, 'packed': 6, 'packed_quads': 24, 'poles': r['faces']['poles'], 'removed_knot_lines': 0}",
      "0 < r['faces']['poles'] < r['patches']['poles']",
      "r['sharpened_edges'] == 0 and r['sharpened_vertices'] == 0 and r['warnings'] == []",
  };
  for (const char* condition : conditions)
    EXPECT_EQ(python_json_check(report, condition), 0) << condition << "\n" << read_text(report);
  EXPECT_NE(python_json_check(report, "r['patches']['total'] == 25"), 0);  // the check can fail
}

// --threads: the conversion on that many threads (the report says so), the same file to the bit.
TEST(CliConvert, ThreadsGiveTheSameFile) {
  TempDir dir;
  const std::string cage = quote(std::string(SUBD2NURBS_CORPUS_DIR) + "/catmark_pole8.obj");
  for (const char* n : {"1", "2"}) {
    const std::string out = dir.file(std::string("t") + n + ".brep"), report = dir.file(std::string("t") + n + ".json");
    const Result r = run("convert " + cage + " -o " + quote(out) + " --report " + quote(report) + " -q --threads " + n);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(python_json_check(report, std::string("r['timings_ms']['threads'] == min(") + n +
                                            ", __import__('os').cpu_count())"),
              0)
        << read_text(report);
  }
  EXPECT_EQ(read_text(dir.file("t1.brep")), read_text(dir.file("t2.brep")));
  const Result bad = run("convert " + cage + " -o " + quote(dir.file("x.brep")) + " --threads 0");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("threads"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("must be 1 .. 1024"), std::string::npos) << bad.err;
}

TEST(CliConvert, FacesPackedOrPerQuad) {
  TempDir dir;
  const std::string torus = quote(std::string(SUBD2NURBS_CORPUS_DIR) + "/catmark_torus.obj");  // 8 x 4 regular quads
  ASSERT_EQ(run("convert " + torus + " -o " + quote(dir.file("p.step")) + " --report " + quote(dir.file("p.json"))).exit_code, 0);
  ASSERT_EQ(run("convert " + torus + " --faces per-quad -o " + quote(dir.file("q.step")) + " --report " +
                quote(dir.file("q.json"))).exit_code, 0);
  EXPECT_EQ(python_json_check(dir.file("p.json"),
                              "r['faces'] == {'mode': 'packed', 'total': 1, 'packed': 1, 'packed_quads': 32, "
                              "'poles': 11 * 7, 'removed_knot_lines': 0} and r['brep']['faces'] == 1 and "
                              "r['brep']['type'] == 'solid' and r['brep']['valid'] and r['curves']['total'] == 2 and "
                              "r['brep']['edges'] == 2 and r['brep']['vertices'] == 1"),
            0);
  EXPECT_EQ(python_json_check(dir.file("q.json"),
                              "r['faces']['mode'] == 'per-quad' and r['faces']['total'] == r['brep']['faces'] == 32 and "
                              "r['faces']['poles'] == 32 * 16 and r['curves']['total'] == 64"),
            0);
  // The patch JSON lists a packed face's quads.
  ASSERT_EQ(run("convert " + torus + " -o " + quote(dir.file("p.json2.json"))).exit_code, 0);
  EXPECT_EQ(python_json_check(dir.file("p.json2.json"),
                              "len(r['patches']) == 1 and len(r['patches'][0]['cells']) == 32 and "
                              "sorted(c['base_face'] for c in r['patches'][0]['cells']) == list(range(32))"),
            0);
  EXPECT_EQ(run("convert " + torus + " --faces some -o " + quote(dir.file("x.step"))).exit_code, 1);
}

/// Two cube cages: 0.4 apart they interpenetrate (OCCT's BOPAlgo_ArgumentAnalyzer agrees:
/// tests/occt/test_self_intersection.cpp), 1.2 apart their convex hulls are disjoint.
TEST(CliConvert, OverlappingPartsAreAWarningNotAFailure) {
  TempDir dir;
  for (const double dx : {0.4, 1.2}) {
    std::ofstream obj(dir.file("cubes.obj"));
    for (const double c : {0.0, dx})
      for (int k = 0; k < 8; ++k)
        obj << "v " << (k & 1 ? 0.5 : -0.5) + c << " " << (k & 2 ? 0.5 : -0.5) + 0.1 * c << " "
            << (k & 4 ? 0.5 : -0.5) + 0.2 * c << "\n";
    for (const int base : {1, 9})
      for (const auto& f : {std::array<int, 4>{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}})
        obj << "f " << base + f[0] << " " << base + f[1] << " " << base + f[2] << " " << base + f[3] << "\n";
    obj.close();
    const Result r = run("convert " + quote(dir.file("cubes.obj")) + " -o " + quote(dir.file("c.brep")) + " --report " +
                            quote(dir.file("c.json")));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const bool overlap = dx < 1;
    EXPECT_EQ(r.err.find("separate parts overlap") != std::string::npos, overlap) << r.err;
    EXPECT_EQ(python_json_check(dir.file("c.json"),
                                overlap ? "(lambda x: x['components'] == 2 and x['crossing_face_pairs'] == 0 and "
                                          "x['overlap_face_pairs'] > 0 and x['overlapping_components'] == [[0, 1]] and "
                                          "all(o['components'] == [0, 1] and not o['inside'] for o in x['overlaps']))"
                                          "(r['self_intersection']) and any('parts overlap' in w for w in r['warnings'])"
                                        : "r['self_intersection']['overlap_face_pairs'] == 0 and r['warnings'] == []"),
              0);
  }
}

TEST(CliConvert, ReportIsDeterministicApartFromTimings) {
  TempDir dir;
  std::string reports[2];
  for (int i = 0; i < 2; ++i) {
    const std::string report = dir.file("r" + std::to_string(i) + ".json");
    ASSERT_EQ(run("convert " + quote(sample()) + " -o " + quote(dir.file("b.json")) + " -q --report " +
                  quote(report)).exit_code, 0);
    reports[i] = std::regex_replace(read_text(report), std::regex("\"timings_ms\": \\{[^}]*\\}|\"quality(_wait)?_ms\": [0-9.e+-]*"), "");
  }
  EXPECT_EQ(reports[0], reports[1]);
  EXPECT_NE(reports[0].find("\"deviation\""), std::string::npos);
}

TEST(CliConvert, LevelAndToleranceChooseTheLevel) {
  TempDir dir;
  const std::string out = dir.file("b.brep"), report = dir.file("r.json");
  ASSERT_EQ(run("convert " + quote(sample()) + " -o " + quote(out) + " --level 1 -q --report " + quote(report)).exit_code, 0);
  EXPECT_EQ(python_json_check(report, "r['level'] == 3 and r['extra_levels'] == 1"), 0) << read_text(report);

  // A relative tolerance that two extra levels reach (the deviation falls ~4x per level at the
  // valence-3 vertices, from 1.7e-3 of the model size).
  const Result met = run("convert " + quote(sample()) + " -o " + quote(out) + " --tolerance 2e-4 -q --report " + quote(report));
  ASSERT_EQ(met.exit_code, 0) << met.err;
  EXPECT_TRUE(met.err.empty()) << met.err;
  EXPECT_EQ(python_json_check(report,
                              "(lambda t: t['met'] and not t['capped'] and t['units'] == 'relative' "
                              "and t['extra_levels_used'] > 0 and t['fans_deepened'] == 8 and not t['default'] "
                              "and t['achieved'] == r['deviation']['max'] "
                              "<= t['requested_model_units'] and abs(t['requested_model_units'] - 2e-4 * r['model_size']) < 1e-18 "
                              "and t['initial_max'] > t['requested_model_units'])(r['deviation']['tolerance'])"),
            0)
      << read_text(report);

  // An absolute tolerance out of reach: capped, not met, still exit 0, with a warning.
  const Result missed = run("convert " + quote(sample()) + " -o " + quote(out) +
                            " --tolerance 1e-12 --absolute -q --report " + quote(report));
  ASSERT_EQ(missed.exit_code, 0) << missed.err;
  EXPECT_NE(missed.err.find("tolerance NOT met"), std::string::npos) << missed.err;
  EXPECT_NE(missed.err.find("using 12"), std::string::npos) << missed.err;
  EXPECT_EQ(python_json_check(report,
                              "(lambda t: (not t['met']) and t['capped'] and t['units'] == 'model' "
                              "and t['extra_levels_used'] == 12 and t['extra_levels_needed'] > 12 and r['level'] == 14 "
                              "and len(r['warnings']) == 2)(r['deviation']['tolerance'])"),
            0)
      << read_text(report);
}

TEST(CliConvert, InvalidInputExitsWith2NamingFileAndLine) {
  TempDir dir;
  const std::string bad = data("invalid/nonmanifold_edge.obj");
  const Result r = run("convert " + quote(bad) + " -o " + quote(dir.file("o.step")) + " --report " +
                       quote(dir.file("r.json")));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(bad + ":12: error: non-manifold edge"), std::string::npos) << r.err;
  EXPECT_TRUE(dir.entries().empty());
}

TEST(CliConvert, UnwritableOutputExitsWith3AndWritesNothing) {
  TempDir dir;
  const std::string out = dir.file("no/such/dir/o.step");
  const Result r = run("convert " + quote(sample()) + " -o " + quote(out) + " --report " + quote(dir.file("r.json")));
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find(out), std::string::npos) << r.err;
  EXPECT_TRUE(dir.entries().empty());
  // The same when only the report cannot be written: nothing, not even the output.
  const std::string report = dir.file("missing/r.json");
  const Result r2 = run("convert " + quote(sample()) + " -o " + quote(dir.file("o.step")) + " --report " + quote(report));
  EXPECT_EQ(r2.exit_code, 3) << r2.err;
  EXPECT_NE(r2.err.find(report), std::string::npos) << r2.err;
  EXPECT_TRUE(dir.entries().empty());
}

TEST(CliConvert, UsageErrorsExitWith1AndWriteNothing) {
  TempDir dir;
  const std::string in = quote(sample()), out = quote(dir.file("o.step"));
  const Result both = run("convert " + in + " -o " + out + " --level 1 --tolerance 1e-3");
  EXPECT_EQ(both.exit_code, 1);
  EXPECT_NE(both.err.find("--tolerance"), std::string::npos) << both.err;
  const Result ext = run("convert " + in + " -o " + quote(dir.file("o.obj")));
  EXPECT_EQ(ext.exit_code, 1);
  EXPECT_NE(ext.err.find("o.obj"), std::string::npos) << ext.err;
  EXPECT_EQ(run("convert " + in + " -o " + quote(dir.file("o"))).exit_code, 1);  // no extension
  EXPECT_EQ(run("convert " + in).exit_code, 1);                                    // no -o
  EXPECT_EQ(run("convert " + in + " -o " + out + " --level -1").exit_code, 1);
  EXPECT_EQ(run("convert " + in + " -o " + out + " --tolerance 0").exit_code, 1);
  EXPECT_EQ(run("convert " + in + " -o " + out + " --absolute").exit_code, 1);  // needs --tolerance
  EXPECT_EQ(run("convert " + in + " -o " + out + " --schema ap203").exit_code, 1);
  const Result deep = run("convert " + in + " -o " + out + " --level 13");
  EXPECT_EQ(deep.exit_code, 1);
  EXPECT_NE(deep.err.find("--level"), std::string::npos) << deep.err;
  EXPECT_TRUE(dir.entries().empty());
}

TEST(CliConvert, Ap242SchemaReachesTheStepHeader) {
  TempDir dir;
  const std::string out = dir.file("b.step");
  ASSERT_EQ(run("convert " + quote(sample()) + " -o " + quote(out) + " --schema ap242 -q").exit_code, 0);
  EXPECT_NE(read_text(out).find("AP242_MANAGED_MODEL_BASED_3D_ENGINEERING"), std::string::npos);
  ASSERT_EQ(run("convert " + quote(sample()) + " -o " + quote(out) + " -q").exit_code, 0);
  EXPECT_NE(read_text(out).find("AUTOMOTIVE_DESIGN"), std::string::npos);
}

TEST(CliConvert, SemiSharpCreasesAreRefinedExactlyWithoutALevelCap) {
  // A cube whose edges are all semi-sharp with sharpness 8: uniform decay lowers it by 1 per
  // level, so no piece touching an edge can be one bicubic before level 8. Nothing is made
  // sharp and nothing is warned about.
  TempDir dir;
  std::string obj =
      "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
      "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
  const int edges[12][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6},
                            {6, 7}, {7, 4}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
  for (const auto& e : edges)
    obj += "t crease 2/1/0 " + std::to_string(e[0]) + " " + std::to_string(e[1]) + " 8\n";
  const std::string cube = dir.write("cube.obj", obj);
  const std::string report = dir.file("r.json");
  const Result r = run("convert " + quote(cube) + " -o " + quote(dir.file("c.step")) + " -q --report " + quote(report));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("made infinitely sharp"), std::string::npos) << r.err;
  EXPECT_EQ(python_json_check(report, "r['sharpened_edges'] == 0 and r['level'] >= 8 and r['warnings'] == []"), 0)
      << read_text(report);
}

TEST(CliConvert, ApproximateFansReportTheirNormalJump) {
  // catmark_val2_interior: its interior valence-2 vertices without a sharp edge have no exact
  // construction (approximate fans, C0 rays), and the report lists each with its normal jump.
  const std::string file = data("corpus/catmark_val2_interior.obj");
  const SubdivLevel level = SubdivLevel::from_input(read_obj(file).input);
  const PolyMesh& m = level.mesh;
  std::string expected;
  int count = 0;
  for (int v = 0; v < m.num_vertices(); ++v) {
    if (m.is_boundary_vertex(v) || m.valence(v) != 2 || level.vertex_sharpness[v] > 0) continue;
    bool sharp = false;
    for (int e = 0; e < m.num_edges(); ++e)
      sharp = sharp || ((m.edge_vertex(e, 0) == v || m.edge_vertex(e, 1) == v) &&
                        level.edge_sharpness[e] >= kInfiniteSharpness);
    if (sharp) continue;
    expected += (expected.empty() ? "" : ", ") + std::to_string(v);
    ++count;
  }
  ASSERT_GT(count, 0);

  TempDir dir;
  const std::string report = dir.file("r.json");
  const Result r = run("convert " + quote(file) + " -o " + quote(dir.file("p.json")) + " -q --report " + quote(report));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string fans = "r['fans']['approximate_fans']";
  EXPECT_EQ(python_json_check(report, "r['brep'] is None and r['output_format'] == 'JSON' and r['step_schema'] is None"), 0);
  EXPECT_EQ(python_json_check(report, "sorted(a['base_vertex'] for a in " + fans + ") == [" + expected + "]"), 0)
      << expected << "\n" << read_text(report);
  EXPECT_EQ(python_json_check(report, "r['fans']['approximate'] == " + std::to_string(count)), 0);
  EXPECT_EQ(python_json_check(report, "all(a['valence'] == 2 and a['rays'] == 2 and a['normal_angle_deg'] is not None "
                                      "for a in " + fans + ")"), 0) << read_text(report);
  // C0 rays: the normals do jump across them (by how much is what the report is for).
  EXPECT_EQ(python_json_check(report, "max(a['normal_angle_deg'] for a in " + fans + ") > 0.1"), 0);
}

// glTF holds triangles only: the CLI rebuilds the quads (core/mesh/quad_recovery.h), says so
// in `info`, and converts the .glb like the cage it came from. Oracle: the OBJ cage.
TEST(CliGltf, InfoReportsRecoveredQuadsAndConvertMatchesTheObj) {
  TempDir dir;
  const LoadedCage cage = read_obj(sample());
  const int quads = cage.input.num_faces();
  const std::string glb = dir.file("box.glb");
  subd2nurbs::testing::GltfOptions o;
  o.split_vertices = true;
  subd2nurbs::testing::write_gltf(cage.input, glb, o);

  const Result info = run("info " + quote(glb));
  EXPECT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE(info.out.find("recovered    " + std::to_string(quads) + " quads from " + std::to_string(2 * quads) +
                          " triangles (0 triangles kept"),
            std::string::npos)
      << info.out;
  const Result info_json = run("info --json " + quote(glb));
  EXPECT_EQ(info_json.exit_code, 0);
  {
    std::ofstream(dir.file("info.json")) << info_json.out;
  }
  EXPECT_EQ(python_json_check(dir.file("info.json"), "r['quad_recovery']['quads'] == " + std::to_string(quads) +
                                                         " and r['faces'] == " + std::to_string(quads)),
            0);

  const Result from_glb = run("convert " + quote(glb) + " -o " + quote(dir.file("glb.step")) + " --report " +
                              quote(dir.file("glb.json")) + " -q");
  ASSERT_EQ(from_glb.exit_code, 0) << from_glb.err;
  const Result from_obj = run("convert " + quote(sample()) + " -o " + quote(dir.file("obj.step")) + " --report " +
                              quote(dir.file("obj.json")) + " -q");
  ASSERT_EQ(from_obj.exit_code, 0) << from_obj.err;
  EXPECT_EQ(python_json_check(dir.file("glb.json"), "r['brep']['type'] == 'solid' and r['brep']['valid']"), 0);
  // The sample's creases are not in the glTF (it has no tags), so only the counts agree.
  EXPECT_EQ(python_json_check(dir.file("glb.json"),
                              "r['patches']['total'] == json.load(open('" + dir.file("obj.json") +
                                  "'))['patches']['total'] == " + std::to_string(quads) +
                                  " and r['brep']['faces'] == json.load(open('" + dir.file("obj.json") +
                                  "'))['brep']['faces']"),
            0);
  EXPECT_TRUE(std::filesystem::is_regular_file(dir.file("glb.step")));
  // check and limit read it like convert does.
  const Result check = run("check " + quote(glb) + " -q --json " + quote(dir.file("check.json")));
  ASSERT_EQ(check.exit_code, 0) << check.err;
  EXPECT_EQ(python_json_check(dir.file("check.json"), "r['patches'] == " + std::to_string(quads)), 0);
  {
    std::ofstream(dir.file("q.txt")) << "0 0.5 0.5\n";
  }
  const Result limit = run("limit " + quote(glb) + " " + quote(dir.file("q.txt")));
  ASSERT_EQ(limit.exit_code, 0) << limit.err;
  EXPECT_EQ(std::count(limit.out.begin(), limit.out.end(), '\n'), 1);

  // A file that is not glTF: exit 2 naming it.
  {
    std::ofstream(dir.file("bad.glb")) << "nope";
  }
  const Result bad = run("convert " + quote(dir.file("bad.glb")) + " -o " + quote(dir.file("bad.step")));
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("bad.glb"), std::string::npos) << bad.err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("bad.step")));
}
