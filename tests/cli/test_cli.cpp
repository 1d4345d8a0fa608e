// The subd2nurbs executable end to end: exit codes, what goes to stdout and stderr.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <map>
#include <regex>
#include <string>

#include "io/obj_reader.h"
#include "io/temp_dir.h"

using namespace subd2nurbs;
using subd2nurbs::testing::read_text;
using subd2nurbs::testing::TempDir;

namespace {

struct Result {
  int exit_code = -1;
  std::string out, err;
};

std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

/// Runs subd2nurbs with the given (already quoted) arguments.
Result run(const std::string& args) {
  TempDir dir;
  const std::string command = quote(SUBD2NURBS_EXE) + " " + args + " >" +
                              quote(dir.file("out")) + " 2>" + quote(dir.file("err"));
  const int status = std::system(command.c_str());
  Result r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = read_text(dir.file("out"));
  r.err = read_text(dir.file("err"));
  return r;
}

std::string sample() { return std::string(SUBD2NURBS_SAMPLES_DIR) + "/rounded_box.obj"; }
std::string data(const std::string& name) {
  return std::string(SUBD2NURBS_TEST_DATA_DIR) + "/" + name;
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
    const SubdivLevel level = load_and_validate(read_obj(file));
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
  EXPECT_NO_THROW(load_and_validate(cage));
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
  const Result version = run("--version");
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_EQ(version.out.rfind("subd2nurbs ", 0), 0u) << version.out;
}
