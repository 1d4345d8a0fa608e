#include "converter/cli/commands.h"

#include <CLI/CLI.hpp>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <new>
#include <vector>

#include "converter/cli/convert.h"
#include "converter/cli/limit_cmd.h"
#include "converter/cli/check_cmd.h"
#include "converter/cli/fair_cmd.h"
#include "converter/cli/fit_cmd.h"
#include "core/fit/interpolate.h"
#include "converter/occt/export_error.h"
#include "core/analysis/mesh_stats.h"
#include "core/polar/polar_refine.h"
#include "core/polar/polar_structure.h"
#include "core/refine/refiner.h"
#include "io/cage_reader.h"
#include "io/input_error.h"
#include "io/obj_reader.h"
#include "io/obj_writer.h"
#include "io/atomic_file.h"
#include "io/input_file.h"
#include "io/json_writer.h"
#include "converter/pipeline/conversion.h"

#ifndef SUBD2NURBS_VERSION
#define SUBD2NURBS_VERSION "0.1.0"
#endif

namespace subd2nurbs::cli {

namespace {

/// Above this many output faces, refine reports what it is doing on stderr.
constexpr double kProgressFaces = 100e3;

const char* kExitCodeHelp =
    "Exit codes:\n"
    "  0  success\n"
    "  1  usage error (unknown option, missing or bad argument)\n"
    "  2  invalid input (unreadable file, malformed OBJ, invalid cage); the message names\n"
    "     FILE:LINE of the offending vertex, face or tag\n"
    "  3  the output file could not be written (an existing file is left untouched)\n"
    "  4  internal error, or the export failed (OCCT refused the shape or the B-rep is not\n"
    "     valid; nothing is written)";

std::string number(double x) {
  if (!std::isfinite(x)) return "-";  // never "nan" / "inf" in a description
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.6g", x);
  return buffer;
}

// --- info as text --------------------------------------------------------------------------

std::string histogram_text(const std::map<int, int>& histogram, const char* unit) {
  std::string s;
  for (const auto& [key, count] : histogram)
    s += (s.empty() ? "" : ", ") + std::to_string(count) + " " + unit + " " + std::to_string(key);
  return s.empty() ? "-" : s;
}

/// What the USD reader read: the layer, each mesh with its scheme and tags, the variant sets.
void print_usd_text(std::ostream& out, const LoadedCage::UsdInfo& u) {
  if (!u.applied) return;
  out << "  usd          " << u.encoding << " " << u.version << ", metersPerUnit "
      << (u.meters_per_unit > 0 ? number(u.meters_per_unit) : std::string("not authored (0.01)")) << ", upAxis "
      << (u.up_axis.empty() ? std::string("not authored (Y)") : u.up_axis) << ", " << u.meshes.size()
      << (u.meshes.size() == 1 ? " mesh\n" : " meshes\n");
  constexpr size_t kListed = 50;
  for (size_t i = 0; i < u.meshes.size() && i < kListed; ++i) {
    const auto& m = u.meshes[i];
    out << "    mesh " << m.path << ": " << m.vertices << " vertices, " << m.faces << " faces, " << m.scheme << ", "
        << m.creases << " crease edges, " << m.corners << " corners, " << m.holes << " holes\n";
  }
  if (u.meshes.size() > kListed) out << "    " << u.meshes.size() - kListed << " more meshes\n";
  for (const auto& v : u.variant_sets) {
    out << "    variant set " << v.prim << " " << v.name << " = "
        << (v.selection.empty() ? std::string("(none)") : v.selection) << " (of ";
    for (size_t i = 0; i < v.variants.size(); ++i) out << (i ? ", " : "") << v.variants[i];
    out << ")\n";
  }
}

void write_usd_json(JsonWriter& w, const LoadedCage::UsdInfo& u) {
  w.key("usd");
  if (!u.applied) {
    w.null();
    return;
  }
  w.begin_object();
  w.members("encoding", u.encoding, "version", u.version, "meters_per_unit", u.meters_per_unit, "up_axis", u.up_axis);
  w.key("meshes").begin_array(4, 2);
  for (const auto& m : u.meshes)
    w.begin_object()
        .members("path", m.path, "vertices", m.vertices, "faces", m.faces, "scheme", m.scheme, "crease_edges", m.creases,
                 "corners", m.corners, "holes", m.holes)
        .end_object();
  w.end_array().key("variant_sets").begin_array(4, 2);
  for (const auto& v : u.variant_sets) {
    w.begin_object().members("prim", v.prim, "name", v.name, "selection", v.selection).key("variants").begin_array();
    for (const std::string& name : v.variants) w.string(name);
    w.end_array().end_object();
  }
  w.end_array().end_object();
}

void print_text(std::ostream& out, const LoadedInput& loaded, const MeshStats& s, const pipeline::InputRoute& route) {
  const SubdivOptions& o = loaded.level.options;
  const BoundingBox& b = s.bounds;
  out << loaded.cage.path << "\n"
      << "  vertices     " << s.vertices << " (" << s.unused_vertices << " unused, "
      << s.extraordinary_vertices << " extraordinary)\n"
      << "  faces        " << s.faces << " (" << histogram_text(s.face_sizes, "of size")
      << "; " << s.holes << " holes)\n"
      << "  edges        " << s.edges << " (" << s.boundary_edges << " on the boundary)\n"
      << "  valences     " << histogram_text(s.valences, "of valence") << "\n"
      << "  boundary     "
      << (s.closed ? std::string("closed")
                   : std::to_string(s.boundary_loops) + " loops, " +
                         std::to_string(s.boundary_vertices) + " vertices, " +
                         std::to_string(s.topological_corners) + " corners")
      << "\n"
      << "  creases      " << s.infinite_crease_edges << " infinitely sharp edges, "
      << s.semi_sharp_crease_edges << " semi-sharp edges, " << s.corner_vertices
      << " corner vertices\n"
      << "  topology     " << s.components << (s.components == 1 ? " component" : " components")
      << ", Euler characteristic " << s.euler_characteristic << "\n"
      << "  bounds       [" << number(b.min[0]) << ", " << number(b.min[1]) << ", "
      << number(b.min[2]) << "] .. [" << number(b.max[0]) << ", " << number(b.max[1]) << ", "
      << number(b.max[2]) << "], diagonal " << number(b.diagonal) << "\n"
      << "  options      boundary " << to_string(o.boundary) << ", creases "
      << to_string(o.crease_method) << ", triangles " << to_string(o.triangles)
      << "\n";
  out << "  path         " << (route.mesh ? "mesh" : "cage") << ": " << route.reason << "\n";
  const LoadedCage::QuadRecovery& q = loaded.cage.recovery;
  if (q.applied)
    out << "  recovered    " << q.quads << " quads from " << q.source_triangles << " triangles ("
        << q.triangles_kept << " triangles kept, " << q.fan_vertices << " fan vertices)\n";
  print_usd_text(out, loaded.cage.usd);
  const PolarDetection polar = detect_polar_structures(loaded.level);
  out << "  polar        " << polar.structures.size() << " polar structure"
      << (polar.structures.size() == 1 ? "" : "s");
  for (const PolarStructure& p : polar.structures)
    out << (&p == &polar.structures.front() ? ": " : ", ") << "vertex " << p.pole << " (valence " << p.valence << ")";
  out << "\n";
  constexpr size_t kListed = 20;
  for (size_t i = 0; i < polar.rejected.size() && i < kListed; ++i)
    out << "    not polar: vertex " << polar.rejected[i].vertex << " (valence " << polar.rejected[i].valence
        << "): " << polar.rejected[i].reason << "\n";
  if (polar.rejected.size() > kListed)
    out << "    not polar: " << polar.rejected.size() - kListed << " more all-triangle vertices\n";
  out << "  warnings     " << (loaded.warnings.empty() ? "none" : std::to_string(loaded.warnings.size()))
      << "\n";
  for (const std::string& w : loaded.warnings) out << "    " << w << "\n";
}

// --- info as JSON ----------------------------------------------------------------------------

void write_histogram(JsonWriter& w, const std::map<int, int>& histogram) {
  w.begin_object();
  for (const auto& [key, count] : histogram) w.member(std::to_string(key), count);
  w.end_object();
}

void print_json(std::ostream& out, const LoadedInput& loaded, const MeshStats& s, const pipeline::InputRoute& route) {
  const SubdivOptions& o = loaded.level.options;
  JsonWriter w(JsonWriter::Numbers::Report, JsonWriter::Spacing::Spaced);
  w.begin_object(2);
  w.members("file", loaded.cage.path, "vertices", s.vertices, "faces", s.faces, "edges", s.edges, "corners",
            s.corners);
  write_histogram(w.key("face_sizes"), s.face_sizes);
  write_histogram(w.key("valences"), s.valences);
  w.key("boundary").begin_object();
  w.members("edges", s.boundary_edges, "vertices", s.boundary_vertices, "loops", s.boundary_loops,
            "topological_corners", s.topological_corners);
  w.end_object().key("creases").begin_object();
  w.members("infinite_edges", s.infinite_crease_edges, "semi_sharp_edges", s.semi_sharp_crease_edges,
            "corner_vertices", s.corner_vertices);
  w.end_object();
  w.members("holes", s.holes, "extraordinary_vertices", s.extraordinary_vertices, "unused_vertices",
            s.unused_vertices, "components", s.components, "euler_characteristic", s.euler_characteristic,
            "closed", s.closed);
  w.key("bounds").begin_object();
  w.key("min").point(s.bounds.min).key("max").point(s.bounds.max).member("diagonal", s.bounds.diagonal);
  w.end_object().key("options").begin_object();
  w.members("boundary", to_string(o.boundary), "crease_method", to_string(o.crease_method), "triangles",
            to_string(o.triangles));
  w.end_object().key("path").begin_object();
  w.members("kind", route.mesh ? "mesh" : "cage", "reason", route.reason);
  w.end_object().key("quad_recovery");
  const LoadedCage::QuadRecovery& q = loaded.cage.recovery;
  if (q.applied) {
    w.begin_object();
    w.members("source_triangles", q.source_triangles, "quads", q.quads, "triangles_kept", q.triangles_kept,
              "fan_vertices", q.fan_vertices);
    w.end_object();
  } else {
    w.null();
  }
  write_usd_json(w, loaded.cage.usd);
  const PolarDetection polar = detect_polar_structures(loaded.level);
  w.key("polar_structures").begin_array();
  for (const PolarStructure& p : polar.structures)
    w.begin_object().members("vertex", p.pole, "valence", p.valence).end_object();
  w.end_array().key("not_polar").begin_array(4, 2);
  for (const RejectedPole& r : polar.rejected)
    w.begin_object().members("vertex", r.vertex, "valence", r.valence, "reason", r.reason).end_object();
  w.end_array().key("warnings").begin_array(4, 2);
  for (const std::string& warning : loaded.warnings) w.string(warning);
  w.end_array().end_object();
  out << w.text() << "\n";
}

}  // namespace

// --- loading and output checks shared by the subcommands ---------------------------------

UsdReadOptions& usd_read_options() {
  static UsdReadOptions options;
  return options;
}

void check_outputs(const std::string& input, const std::vector<std::pair<std::string, std::string>>& outputs) {
  namespace fs = std::filesystem;
  std::vector<std::pair<std::string, std::string>> seen;  // (option, absolute target)
  for (const auto& [option, path] : outputs) {
    if (path.empty()) continue;
    const std::string target = resolve_output_path(path);
    if (same_file(input, target))
      throw UsageError(option + " " + printable(path) + " is the input file " + printable(input) +
                       " (the same file); the input is never overwritten: choose another output name");
    std::error_code ec;
    std::string absolute = fs::weakly_canonical(fs::absolute(target, ec), ec).string();
    if (absolute.empty()) absolute = target;
    for (const auto& [other_option, other] : seen)
      if (other == absolute || same_file(other, target))
        throw UsageError(option + " and " + other_option + " name the same file " + printable(path) +
                         ": give each output its own name");
    seen.emplace_back(option, absolute);
  }
}

CLI::App* add_cage_command(CLI::App& app, const std::string& name, const std::string& description,
                           std::string& mesh) {
  CLI::App* command = app.add_subcommand(name, description);
  command->add_option("MESH", mesh,
                      "OBJ cage (with OpenSubdiv 't' tags), USD (.usd/.usda/.usdc/.usdz, creases kept), glTF / GLB "
                      "triangles (quads recovered), or STL / PLY / OFF")
      ->required();
  command->add_option_function<std::vector<std::string>>(
      "--variant",
      [](const std::vector<std::string>& selections) {
        for (const std::string& s : selections) {
          try {
            add_variant_selection(usd_read_options(), s);
          } catch (const Error& e) {
            throw CLI::ValidationError("--variant", e.what());
          }
        }
      },
      "USD input: select variant NAME of variant set SET (SET=NAME; may be repeated); default: the file's "
      "selection, else the first variant")
      ->type_name("SET=NAME")
      ->allow_extra_args(false);  // one SET=NAME per --variant: MESH is never taken for one
  return command;
}

LoadedInput load_input(const std::string& path) { return pipeline::load_input(path, usd_read_options()); }

void add_limit_options(CLI::App& command, LimitOptionValues& values, const std::string& faces_meaning) {
  command.add_option_function<double>(
      "--max-faces", [&values](const double& n) { values.max_faces = n; },
      "Refuse when " + faces_meaning + " would exceed N");
  command.add_option("--max-memory", values.max_memory,
                     "Refuse when the estimated memory would exceed SIZE (bytes, or with K/M/G/T; default "
                     "3/4 of the memory available)");
}

pipeline::ResourceLimits resource_limits(const LimitOptionValues& values) {
  pipeline::ResourceLimits limits;
  limits.max_faces = values.max_faces;
  if (!values.max_memory.empty()) limits.max_memory = pipeline::memory_size(values.max_memory);
  pipeline::validate(limits);
  return limits;
}

void DiagnosticPrinter::operator()(const pipeline::ConversionDiagnostic& d) {
  if (quiet_ && d.severity == pipeline::Severity::Note) return;
  if (d.code == pipeline::DiagnosticCode::PoleNotPolar) poles_.push_back(d);
  else err_ << pipeline::report_text(d) << "\n";
}

void DiagnosticPrinter::finish() {
  if (poles_.size() <= kListedPoles) {
    for (const pipeline::ConversionDiagnostic& d : poles_) err_ << pipeline::report_text(d) << "\n";
  } else {
    std::map<std::string, int> by_category;
    int mendable = 0;
    std::string remedy;  // the setting that may make them polar caps
    for (const pipeline::ConversionDiagnostic& d : poles_) {
      ++by_category[d.category];
      mendable += !d.remedy.empty();
      if (!d.remedy.empty()) remedy = d.remedy;
    }
    std::string counts;
    for (const auto& [category, count] : by_category)
      counts += (counts.empty() ? "" : ", ") + std::to_string(count) + ": " + category;
    err_ << "subd2nurbs: note: " << poles_.size() << " vertices are not polar structures, Catmull-Clark is used there ("
         << counts << ")";
    if (mendable > 0) err_ << "; " << option_name(remedy) << " may make " << mendable << " of them polar caps";
    err_ << "; `subd2nurbs info --json` lists them all\n";
  }
  poles_.clear();
}

std::string error_message(const Error& e, const std::string& input) {
  if (const auto* s = dynamic_cast<const pipeline::SettingsError*>(&e))
    return "subd2nurbs: error: " + option_name(s->setting()) + " " + s->rule();
  if (const auto* i = dynamic_cast<const InputError*>(&e)) return i->location() + ": error: " + i->message();
  switch (e.kind()) {
    case ErrorKind::Input:  // found after validation (e.g. every face a hole): about the cage as a whole
      return printable(input) + ": error: " + e.what();
    case ErrorKind::Write: return std::string("subd2nurbs: cannot write ") + e.what();
    case ErrorKind::Export: return std::string("subd2nurbs: export failed: ") + e.what();
    default: return std::string("subd2nurbs: error: ") + e.what();
  }
}

std::string option_name(const std::string& setting) {
  if (const pipeline::SettingRow* row = pipeline::find_setting(setting); row && !row->cli.empty()) return row->cli;
  std::string name = "--" + setting;
  std::replace(name.begin(), name.end(), '_', '-');
  return name;
}

void add_setting_options(CLI::App& app, pipeline::SettingCommand command, SettingValues& values,
                         const std::vector<pipeline::SettingRow>& table) {
  using pipeline::SettingType;
  for (const pipeline::SettingRow& row : table) {
    if (row.cli.empty() || !(row.commands & command)) continue;
    const std::string name = row.name;
    auto store = [&values, name](pipeline::SettingValue v) { values.emplace_back(name, std::move(v)); };
    std::string help = row.help;
    if (row.type != SettingType::Flag) {
      const std::string d = std::holds_alternative<std::monostate>(row.default_value)
                                ? row.default_text
                                : pipeline::value_text(row, row.default_value);
      if (!d.empty()) help += " (default: " + d + ")";
    }
    switch (row.type) {
      case SettingType::Flag:
        app.add_flag_callback(row.cli, [store] { store(true); }, help);
        break;
      case SettingType::Integer:
        app.add_option_function<int>(row.cli, [store](const int& x) { store(static_cast<long long>(x)); }, help);
        break;
      case SettingType::Number:
        app.add_option_function<double>(row.cli, [store](const double& x) { store(x); }, help);
        break;
      case SettingType::OnOff:
      case SettingType::Word:
      case SettingType::Size:
        app.add_option_function<std::string>(row.cli, [store](const std::string& x) { store(x); }, help);
        break;
    }
  }
}

// --- subcommands ---------------------------------------------------------------------------

void run_info(const InfoOptions& options, std::ostream& out) {
  const LoadedInput loaded = load_input(options.mesh);
  const MeshStats stats = compute_stats(loaded.level, loaded.positions());
  const pipeline::InputRoute route =
      pipeline::route_input(loaded.cage, options.mesh, pipeline::input_kind(options.input));
  if (options.json)
    print_json(out, loaded, stats, route);
  else
    print_text(out, loaded, stats, route);
}

void run_refine(const RefineOptions& options, std::ostream& err) {
  pipeline::check_refine_levels(options.levels);
  const bool polar = pipeline::polar_mode(options.polar);
  resource_limits(options.limits);  // a malformed --max-memory is refused before any work
  check_outputs(options.mesh, {{"-o", options.output}});
  const LoadedInput loaded = load_input(options.mesh);
  for (const std::string& w : loaded.warnings) err << w << "\n";

  const PolyMesh& base = loaded.level.mesh;
  const pipeline::ResourceEstimate estimate = pipeline::estimate_refinement(loaded.level, options.levels);
  pipeline::check_resources(estimate, resource_limits(options.limits), pipeline::kDefaultMaxRefineFaces,
                            "refining " + std::to_string(base.num_faces()) + " faces to level " +
                                std::to_string(options.levels),
                            "use fewer levels");
  const double faces = estimate.faces;
  const bool report = faces > kProgressFaces;

  if (report)
    err << "subd2nurbs: refining " << options.mesh << " to level " << options.levels
        << " (" << number(faces) << " faces)\n";
  std::vector<PolarStructure> structures;
  if (polar) structures = detect_polar_structures(loaded.level).structures;
  const PolarRefinement refined =
      refine_with_polar(loaded.level, loaded.positions(), options.levels, structures);
  if (refined.structures > 0 && report)
    err << "subd2nurbs: " << refined.structures << " polar structures refined by BP subdivision\n";
  if (report) err << "subd2nurbs: writing " << options.output << "\n";
  write_obj(options.output, refined.positions, refined.level);
}

// --- command line --------------------------------------------------------------------------

int run(int argc, const char* const* argv, std::ostream& out, std::ostream& err) {
  CLI::App app{"Catmull-Clark subdivision cages to bicubic NURBS: STEP / IGES / BREP export, "
               "inspection and uniform refinement.",
               "subd2nurbs"};
  app.set_version_flag("--version", std::string("subd2nurbs ") + SUBD2NURBS_VERSION);
  app.footer(kExitCodeHelp);
  app.require_subcommand(1);

  InfoOptions info;
  CLI::App* info_command =
      add_cage_command(app, "info", "Describe a cage: counts, boundary, creases, warnings", info.mesh);
  info_command->add_flag("--json", info.json, "Print JSON on stdout instead of text");
  info_command->add_option("--input", info.input,
                           "auto, mesh or cage: which path `convert` takes (as convert --input; auto: by the rule "
                           "of docs/meshes.md)")
      ->check(CLI::IsMember({"auto", "mesh", "cage"}));

  RefineOptions refine;
  CLI::App* refine_command =
      add_cage_command(app, "refine", "Refine a cage uniformly and write the result as OBJ", refine.mesh);
  refine_command->add_option("-l,--levels", refine.levels,
                             "Number of refinement levels (0 .. " + std::to_string(pipeline::kMaxRefineLevels) + ")")
      ->capture_default_str();
  refine_command->add_option("-o,--output", refine.output, "Output OBJ file")->required();
  refine_command->add_option("--polar", refine.polar,
                             "Polar structures: on (BP subdivision there, default) or off (Catmull-Clark)");
  add_limit_options(*refine_command, refine.limits,
                    "the output faces (default " + number(pipeline::kDefaultMaxRefineFaces) + ")");

  ConvertOptions convert;
  CLI::App* convert_command = add_cage_command(
      app, "convert",
      "Convert a cage to bicubic NURBS patches, written as STEP, IGES, BREP or patch JSON "
      "(by the output's extension), with continuity and deviation measures",
      convert.mesh);
  convert_command
      ->add_option("-o,--output", convert.output,
                   "Output file: .step/.stp, .iges/.igs, .brep, or .json (the patches as JSON)")
      ->required();
  convert_command->add_option("--report", convert.report,
                              "Also write a JSON report (counts, continuity, deviation, timings)");
  convert_command->add_option("--preview", convert.preview,
                              "Also write a GLB preview of the patches with per-vertex colours (see --color)");
  convert_command->add_option("--fit-to", convert.fit_to,
                              "First fit the cage to this target shape (a mesh or point cloud, as `subd2nurbs fit "
                              "--to`, default options), then convert the fitted cage");
  convert_command->add_option("--keep-cage", convert.keep_cage,
                              "Also write the cage that was converted as OBJ with its tags (for a mesh input: the "
                              "quad cage made from it, fitted), for editing");
  add_setting_options(*convert_command, pipeline::kConvertCommand, convert.settings);
  convert_command->add_flag("-q,--quiet", convert.quiet,
                            "No progress, notes or summary on stderr (warnings are still printed)");

  CLI::App* settings_command = app.add_subcommand(
      "settings", "Print every setting of convert (and check) as a Markdown table: the command line's flag, the "
                  "Python keyword, the FreeCAD property, type, default and meaning (docs/settings.md)");

  LimitOptions limit;
  CLI::App* limit_command = add_limit_command(app, limit);
  CheckOptions check;
  CLI::App* check_command = add_check_command(app, check);
  FairCommandOptions fair;
  CLI::App* fair_command = add_fair_command(app, fair);
  FitCommandOptions fit;
  CLI::App* fit_command = add_fit_command(app, fit);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // Help and version requests are successes; app.exit prints them or the error message.
    return app.exit(e, out, err) == 0 ? kOk : kUsage;
  }

  std::string current_input = info.mesh + refine.mesh + convert.mesh + limit.mesh + check.mesh + fit.mesh;
  try {
    if (*settings_command) out << pipeline::settings_markdown();
    if (*info_command) run_info(info, out);
    if (*refine_command) run_refine(refine, err);
    if (*limit_command) run_limit(limit, std::cin, out, err);
    if (*check_command) run_check(check, err);
    if (*fair_command) run_fair(fair, err);
    if (*fit_command) run_fit(fit, err);
    if (*convert_command) {
      convert.progress_tty = &err == &std::cerr && ::isatty(STDERR_FILENO) == 1;
      run_convert(convert, err);
    }
    return kOk;
  } catch (const Error& e) {
    err << error_message(e, current_input) << "\n";
    return pipeline::exit_code(e);
  } catch (const std::bad_alloc&) {
    err << "subd2nurbs: out of memory\n";
    return kInternalError;
  } catch (const std::exception& e) {
    err << "subd2nurbs: internal error: " << e.what() << "\n";
    return kInternalError;
  }
}

}  // namespace subd2nurbs::cli
