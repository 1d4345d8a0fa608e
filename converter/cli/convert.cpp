#include "converter/cli/convert.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <vector>

#include "converter/cli/commands.h"
#include "converter/occt/brep_builder.h"
#include "converter/occt/export_error.h"
#include "converter/occt/writers.h"
#include "core/eval/continuity.h"
#include "core/eval/deviation.h"
#include "core/patch/patch_builder.h"
#include "io/atomic_file.h"
#include "io/input_error.h"
#include "io/obj_reader.h"
#include "io/patch_json.h"

namespace subd2nurbs::cli {

std::string json_string(const std::string& s) {
  std::string r = "\"";
  for (const unsigned char c : s) {
    switch (c) {
      case '"': r += "\\\""; break;
      case '\\': r += "\\\\"; break;
      case '\n': r += "\\n"; break;
      case '\r': r += "\\r"; break;
      case '\t': r += "\\t"; break;
      default:
        if (c < 0x20) {
          char buffer[8];
          std::snprintf(buffer, sizeof buffer, "\\u%04x", c);
          r += buffer;
        } else {
          r += static_cast<char>(c);
        }
    }
  }
  return r + "\"";
}

std::string json_number(double x) {
  if (!std::isfinite(x)) return "null";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", x);
  return buffer;
}

namespace {

/// Level-k faces above which a conversion is refused (--level) or its levels capped
/// (--tolerance): the level-k Bezier nets alone take 384 bytes per face.
constexpr double kMaxLevelFaces = 4e6;
/// Samples per shared curve for the continuity measures.
constexpr int kContinuitySamples = 24;
/// Extra levels of refinement for the deviation samples.
constexpr int kDeviationSampleLevels = 2;

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

std::string short_number(double x) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", x);
  return buffer;
}

std::string json_bool(bool b) { return b ? "true" : "false"; }

std::string json_point(const Point3& p) {
  return "[" + json_number(p[0]) + ", " + json_number(p[1]) + ", " + json_number(p[2]) + "]";
}

enum class OutputKind { Json, Step, Iges, Brep };

OutputKind output_kind(const std::string& path) {
  const std::string ext = std::filesystem::path(path).extension().string();
  std::string lower;
  for (char c : ext) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (lower == ".json") return OutputKind::Json;
  try {
    switch (occt::format_from_path(path)) {
      case occt::Format::Step: return OutputKind::Step;
      case occt::Format::Iges: return OutputKind::Iges;
      case occt::Format::Brep: return OutputKind::Brep;
    }
  } catch (const std::invalid_argument&) {
  }
  throw UsageError("cannot tell the output format from '" + path +
                   "': use .step, .stp, .iges, .igs, .brep or .json");
}

const char* output_kind_name(OutputKind k) {
  switch (k) {
    case OutputKind::Json: return "JSON";
    case OutputKind::Step: return "STEP";
    case OutputKind::Iges: return "IGES";
    case OutputKind::Brep: return "BREP";
  }
  return "?";
}

/// Fails early (before the work) when a file cannot be created in `path`'s directory.
void check_directory(const std::string& path) {
  namespace fs = std::filesystem;
  fs::path dir = fs::path(path).parent_path();
  if (dir.empty()) dir = ".";
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw WriteError(path, "the directory " + dir.string() + " does not exist");
  if (::access(dir.c_str(), W_OK) != 0)
    throw WriteError(path, "the directory " + dir.string() + " is not writable");
}

/// Level-k faces of a build with `extra` levels: one coarse quad becomes 4^(2 + extra).
double level_faces(const SubdivLevel& base, int extra) {
  const PolyMesh& m = base.mesh;
  const double coarse_quads = m.all_quads() ? m.num_faces() : m.num_corners();
  return coarse_quads * std::pow(4.0, 2 + extra);
}

/// Prints stage lines and, for the B-rep, a percentage: in place on a terminal, else a line
/// per 10 % once the stage has taken more than a few seconds.
class Progress {
 public:
  Progress(std::ostream& err, bool quiet, bool tty) : err_(err), quiet_(quiet), tty_(tty) {}

  void stage(const std::string& what) {
    if (!quiet_) err_ << "subd2nurbs: " << what << "...\n" << std::flush;
  }

  std::function<void(double)> percent(const std::string& what) {
    if (quiet_) return {};
    start_ = Clock::now();
    last_ = -1;
    return [this, what](double fraction) {
      const int p = static_cast<int>(std::floor(100 * std::clamp(fraction, 0.0, 1.0)));
      if (tty_) {
        if (p != last_) {
          err_ << "\rsubd2nurbs: " << what << "... " << p << "%" << std::flush;
          open_line_ = true;
        }
      } else if (ms_since(start_) > 3000 && p / 10 != last_ / 10) {
        err_ << "subd2nurbs: " << what << "... " << p << "%\n" << std::flush;
      }
      last_ = p;
    };
  }

  /// Ends an in-place percentage line.
  void done() {
    if (open_line_) err_ << "\n" << std::flush;
    open_line_ = false;
  }

 private:
  std::ostream& err_;
  bool quiet_, tty_;
  Clock::time_point start_;
  int last_ = -1;
  bool open_line_ = false;
};

struct Timings {
  double load = 0, patches = 0, continuity = 0, deviation = 0, brep = 0, write = 0;
};

struct ToleranceResult {
  double requested = 0;  ///< as given
  double absolute = 0;   ///< in model units
  double first_max = 0;  ///< deviation at the minimum level
  int needed = 0;        ///< extra levels extra_levels_for_tolerance asked for
  int used = 0;          ///< after the cap
  bool capped = false;
  std::string cap_reason;
  bool met = false;
};

struct ApproximateFan {
  int base_vertex = -1, valence = 0, sectors = 0, rays = 0;
  double normal_angle_deg = -1;  ///< max over its measured C0 rays, -1 if none was measured
};

struct Conversion {
  std::string input, output;
  OutputKind kind = OutputKind::Step;
  occt::StepSchema schema = occt::StepSchema::AP214;
  std::vector<std::string> warnings;
  PatchBuild build;
  int extra_levels = 0;
  ContinuityReport continuity;
  DeviationReport deviation;
  bool tolerance_given = false, tolerance_absolute = false;
  ToleranceResult tolerance;
  std::array<int, 5> fans_by_mode{};  ///< indexed by FanMode
  std::vector<ApproximateFan> approximate;
  std::array<int, 5> curves_by_continuity{};  ///< indexed by Continuity
  bool has_brep = false;
  occt::BrepResult brep;
  Timings ms;
};

void collect_fans(Conversion& c) {
  const PatchBuildInfo& info = c.build.info;
  std::vector<int> measure_of_curve(c.build.set.curves.size(), -1);
  for (size_t i = 0; i < c.continuity.curves.size(); ++i)
    measure_of_curve[c.continuity.curves[i].curve] = static_cast<int>(i);
  std::vector<int> approximate_of_fan(info.fans.size(), -1);
  for (size_t f = 0; f < info.fans.size(); ++f) {
    const IrregularFan& fan = info.fans[f];
    ++c.fans_by_mode[static_cast<int>(fan.mode)];
    if (fan.mode != FanMode::Approximate) continue;
    approximate_of_fan[f] = static_cast<int>(c.approximate.size());
    c.approximate.push_back({fan.base_vertex, fan.valence, fan.sectors, 0, -1});
  }
  for (const RayCurve& ray : info.rays) {
    if (ray.fan < 0 || approximate_of_fan[ray.fan] < 0 || ray.continuity != Continuity::C0) continue;
    ApproximateFan& a = c.approximate[approximate_of_fan[ray.fan]];
    ++a.rays;
    const int m = measure_of_curve[ray.curve];
    if (m >= 0) a.normal_angle_deg = std::max(a.normal_angle_deg, c.continuity.curves[m].normal_angle_deg);
  }
  for (const BoundaryCurve& bc : c.build.set.curves) ++c.curves_by_continuity[static_cast<int>(bc.continuity)];
}

// --- the report ------------------------------------------------------------------------------

std::string report_json(const Conversion& c) {
  const PatchBuildInfo& info = c.build.info;
  const PatchSet& ps = c.build.set;
  const double size = ps.model_size;
  auto relative = [size](double x) { return size > 0 ? json_number(x / size) : std::string("null"); };
  std::string j;
  auto line = [&j](const std::string& s) { j += s + "\n"; };

  line("{");
  line("  \"format\": \"subd2nurbs-report\",");
  line("  \"version\": 1,");
  line("  \"input\": " + json_string(c.input) + ",");
  line("  \"output\": " + json_string(c.output) + ",");
  line("  \"output_format\": " + json_string(output_kind_name(c.kind)) + ",");
  line("  \"step_schema\": " + (c.kind == OutputKind::Step ? json_string(occt::to_string(c.schema)) : std::string("null")) + ",");
  std::string warnings = "  \"warnings\": [";
  for (size_t i = 0; i < c.warnings.size(); ++i) warnings += (i ? ", " : "") + json_string(c.warnings[i]);
  line(warnings + "],");
  line("  \"model_size\": " + json_number(size) + ",");
  line("  \"coarse_level\": " + std::to_string(info.coarse_level) + ",");
  line("  \"level\": " + std::to_string(info.level) + ",");
  line("  \"extra_levels\": " + std::to_string(c.extra_levels) + ",");
  line("  \"patches\": {\"total\": " + std::to_string(ps.patches.size()) + ", \"regular\": " +
       std::to_string(info.regular_patches) + ", \"pccm\": " + std::to_string(info.pccm_patches) + "},");
  const auto& cc = c.curves_by_continuity;
  line("  \"curves\": {\"total\": " + std::to_string(ps.curves.size()) + ", \"boundary\": " +
       std::to_string(cc[0]) + ", \"c0\": " + std::to_string(cc[1]) + ", \"g1\": " +
       std::to_string(cc[2]) + ", \"c1\": " + std::to_string(cc[3]) + ", \"c2\": " + std::to_string(cc[4]) + "},");
  const auto& fm = c.fans_by_mode;
  line("  \"fans\": {\"smooth\": " + std::to_string(fm[0]) + ", \"dart\": " + std::to_string(fm[1]) +
       ", \"crease\": " + std::to_string(fm[2]) + ", \"corner\": " + std::to_string(fm[3]) +
       ", \"approximate\": " + std::to_string(fm[4]) + ",");
  std::string approx = "    \"approximate_fans\": [";
  for (size_t i = 0; i < c.approximate.size(); ++i) {
    const ApproximateFan& a = c.approximate[i];
    approx += std::string(i ? ",\n      " : "\n      ") + "{\"base_vertex\": " + std::to_string(a.base_vertex) +
              ", \"valence\": " + std::to_string(a.valence) + ", \"sectors\": " + std::to_string(a.sectors) +
              ", \"rays\": " + std::to_string(a.rays) + ", \"normal_angle_deg\": " +
              (a.normal_angle_deg < 0 ? std::string("null") : json_number(a.normal_angle_deg)) + "}";
  }
  line(approx + (c.approximate.empty() ? "]" : "\n    ]") + "},");
  line("  \"sharpened_edges\": " + std::to_string(info.sharpened_edges) + ",");
  line("  \"sharpened_vertices\": " + std::to_string(info.sharpened_vertices) + ",");
  if (c.has_brep) {
    const occt::BrepResult& b = c.brep;
    line("  \"brep\": {\"faces\": " + std::to_string(b.num_faces) + ", \"edges\": " + std::to_string(b.num_edges) +
         ", \"vertices\": " + std::to_string(b.num_vertices) + ", \"type\": " +
         json_string(b.is_solid ? "solid" : "shell") + ", \"solids\": " + std::to_string(b.num_solids) +
         ", \"shells\": " + std::to_string(b.num_shells) + ", \"valid\": " + json_bool(b.valid) +
         ", \"tolerance\": " + json_number(b.tolerance) + "},");
  } else {
    line("  \"brep\": null,");
  }
  const ContinuityReport& k = c.continuity;
  line("  \"continuity\": {\"samples_per_curve\": " + std::to_string(kContinuitySamples) +
       ", \"shared_curves\": " + std::to_string(k.curves.size()) + ",");
  line("    \"max_gap\": " + json_number(k.max_gap) + ", \"max_gap_relative\": " + relative(k.max_gap) + ",");
  line("    \"max_normal_angle_deg\": " + json_number(k.max_normal_angle_deg) +
       ", \"max_coplanarity\": " + json_number(k.max_coplanarity) + ",");
  line("    \"max_c1_jump\": " + json_number(k.max_c1_jump) + ", \"max_c2_jump\": " + json_number(k.max_c2_jump) +
       ", \"max_crease_normal_angle_deg\": " + json_number(k.max_crease_normal_angle_deg) + "},");
  const DeviationReport& d = c.deviation;
  line("  \"deviation\": {\"max\": " + json_number(d.max) + ", \"mean\": " + json_number(d.mean) +
       ", \"relative\": " + relative(d.max) + ",");
  std::string worst = "null";
  if (d.worst_fan >= 0 && d.worst_fan < static_cast<int>(info.fans.size())) {
    const IrregularFan& f = info.fans[d.worst_fan];
    worst = "{\"base_vertex\": " + std::to_string(f.base_vertex) + ", \"valence\": " + std::to_string(f.valence) +
            ", \"mode\": " + json_string(to_string(f.mode)) + "}";
  }
  line("    \"where\": " + (d.samples > 0 ? json_point(d.where) : std::string("null")) + ", \"worst_fan\": " + worst + ",");
  line("    \"samples\": " + std::to_string(d.samples) + ", \"sample_levels\": " + std::to_string(d.sample_levels) + ",");
  if (c.tolerance_given) {
    const ToleranceResult& t = c.tolerance;
    line("    \"tolerance\": {\"requested\": " + json_number(t.requested) + ", \"units\": " +
         json_string(c.tolerance_absolute ? "model" : "relative") + ", \"requested_model_units\": " +
         json_number(t.absolute) + ",");
    line("      \"initial_max\": " + json_number(t.first_max) + ", \"extra_levels_needed\": " +
         std::to_string(t.needed) + ", \"extra_levels_used\": " + std::to_string(t.used) +
         ", \"capped\": " + json_bool(t.capped) + ",");
    line("      \"achieved\": " + json_number(d.max) + ", \"achieved_relative\": " + relative(d.max) +
         ", \"met\": " + json_bool(t.met) + "}},");
  } else {
    line("    \"tolerance\": null},");
  }
  const Timings& ms = c.ms;
  line("  \"timings_ms\": {\"load\": " + json_number(ms.load) + ", \"patches\": " + json_number(ms.patches) +
       ", \"continuity\": " + json_number(ms.continuity) + ", \"deviation\": " + json_number(ms.deviation) +
       ", \"brep\": " + json_number(ms.brep) + ", \"write\": " + json_number(ms.write) + "}");
  line("}");
  return j;
}

void print_summary(std::ostream& err, const Conversion& c) {
  const PatchBuildInfo& info = c.build.info;
  const PatchSet& ps = c.build.set;
  const double size = ps.model_size > 0 ? ps.model_size : 1;
  err << "subd2nurbs: wrote " << c.output << " (" << output_kind_name(c.kind);
  if (c.kind == OutputKind::Step) err << " " << occt::to_string(c.schema);
  err << ")\n";
  err << "  patches    " << ps.patches.size() << " (" << info.regular_patches << " regular, "
      << info.pccm_patches << " pccm), level " << info.level << " (coarse level " << info.coarse_level
      << ", " << c.extra_levels << " extra)\n";
  const auto& fm = c.fans_by_mode;
  err << "  fans       " << fm[0] << " smooth, " << fm[1] << " dart, " << fm[2] << " crease, " << fm[3]
      << " corner, " << fm[4] << " approximate\n";
  if (c.has_brep)
    err << "  B-rep      " << (c.brep.is_solid ? "solid" : "shell") << ", " << c.brep.num_faces << " faces, "
        << c.brep.num_edges << " edges, " << c.brep.num_vertices << " vertices, "
        << (c.brep.valid ? "valid" : "NOT valid") << "\n";
  const ContinuityReport& k = c.continuity;
  err << "  gaps       max " << short_number(k.max_gap) << " (" << short_number(k.max_gap / size)
      << " of the model size)\n";
  err << "  smooth     max normal angle " << short_number(k.max_normal_angle_deg)
      << " deg across G1/C1/C2 curves\n";
  double approximate_angle = -1;
  for (const ApproximateFan& a : c.approximate) approximate_angle = std::max(approximate_angle, a.normal_angle_deg);
  if (approximate_angle >= 0)
    err << "  approx.    max normal angle " << short_number(approximate_angle) << " deg across the rays of "
        << c.approximate.size() << " approximate fan(s)\n";
  const DeviationReport& d = c.deviation;
  err << "  deviation  max " << short_number(d.max) << " (" << short_number(d.max / size)
      << " of the model size), mean " << short_number(d.mean);
  if (d.worst_fan >= 0 && d.worst_fan < static_cast<int>(info.fans.size())) {
    const IrregularFan& f = info.fans[d.worst_fan];
    err << ", worst at the " << to_string(f.mode) << " fan of ";
    if (f.base_vertex >= 0) err << "cage vertex " << f.base_vertex;
    else err << "a level-" << info.coarse_level << " vertex";
    err << " (valence " << f.valence << ")";
  }
  err << "\n";
  if (c.tolerance_given)
    err << "  tolerance  " << short_number(c.tolerance.absolute) << " (model units): "
        << (c.tolerance.met ? "met" : "NOT met") << "\n";
}

}  // namespace

// --- the subcommand ------------------------------------------------------------------------

void run_convert(const ConvertOptions& options, std::ostream& err) {
  if (options.level_given && options.tolerance_given)
    throw UsageError("--level and --tolerance exclude each other (--tolerance chooses the level)");
  if (options.level < 0) throw UsageError("--level must be >= 0");
  if (options.tolerance_given && !(options.tolerance > 0 && std::isfinite(options.tolerance)))
    throw UsageError("--tolerance must be a positive number");
  if (options.absolute && !options.tolerance_given) throw UsageError("--absolute needs --tolerance");
  if (options.schema != "ap214" && options.schema != "ap242")
    throw UsageError("--schema must be ap214 or ap242");

  Conversion c;
  c.input = options.mesh;
  c.output = options.output;
  c.kind = output_kind(options.output);
  c.schema = options.schema == "ap242" ? occt::StepSchema::AP242 : occt::StepSchema::AP214;
  c.tolerance_given = options.tolerance_given;
  c.tolerance_absolute = options.absolute;
  check_directory(options.output);
  if (!options.report.empty()) check_directory(options.report);

  Progress progress(err, options.quiet, options.progress_tty);
  auto warn = [&](const std::string& w) {
    err << w << "\n";
    c.warnings.push_back(w);
  };

  // Load.
  auto t = Clock::now();
  progress.stage("reading " + options.mesh);
  const LoadedCage cage = read_obj(options.mesh);
  Diagnostics validation;
  const SubdivLevel base = load_and_validate(cage, &validation);
  for (const Diagnostic& d : cage.diagnostics) warn(format_diagnostic(cage, d));
  for (const Diagnostic& d : validation) warn(format_diagnostic(cage, d));
  const std::vector<Point3> positions(cage.input.positions.begin(), cage.input.positions.end());
  c.ms.load = ms_since(t);

  if (options.level_given && level_faces(base, options.level) > kMaxLevelFaces)
    throw UsageError("--level " + std::to_string(options.level) + " would refine " + options.mesh +
                     " to about " + short_number(level_faces(base, options.level)) +
                     " faces (limit " + short_number(kMaxLevelFaces) + "); use a lower --level");

  // Patches, at the level asked for or at the minimum level first for --tolerance.
  auto build = [&](int extra) {
    const auto t0 = Clock::now();
    progress.stage(extra == 0 ? std::string("building patches")
                              : "building patches (" + std::to_string(extra) + " extra levels)");
    PatchOptions po;
    po.extra_levels = extra;
    c.build = build_patches(base, positions, po);
    c.extra_levels = extra;
    c.ms.patches += ms_since(t0);
  };
  auto measure_deviation_now = [&] {
    const auto t0 = Clock::now();
    progress.stage("measuring the deviation from the limit surface");
    c.deviation = measure_deviation(c.build, kDeviationSampleLevels);
    c.ms.deviation += ms_since(t0);
  };
  build(options.level_given ? options.level : 0);

  if (options.tolerance_given) {
    ToleranceResult& tr = c.tolerance;
    tr.requested = options.tolerance;
    tr.absolute = options.absolute ? options.tolerance : options.tolerance * c.build.set.model_size;
    measure_deviation_now();
    tr.first_max = c.deviation.max;
    tr.needed = std::max(0, extra_levels_for_tolerance(c.build, c.deviation, tr.absolute));
    tr.used = std::min(tr.needed, kMaxToleranceExtraLevels);
    if (tr.used < tr.needed) {
      tr.capped = true;
      tr.cap_reason = "at most " + std::to_string(kMaxToleranceExtraLevels) + " extra levels";
    }
    while (tr.used > 0 && level_faces(base, tr.used) > kMaxLevelFaces) {
      --tr.used;
      tr.capped = true;
      tr.cap_reason = "at most " + short_number(kMaxLevelFaces) + " refined faces";
    }
    if (tr.capped)
      warn("subd2nurbs: warning: the tolerance needs " + std::to_string(tr.needed) +
           " extra levels; using " + std::to_string(tr.used) + " (" + tr.cap_reason + ")");
    if (tr.used > 0) {
      build(tr.used);
      measure_deviation_now();
    }
    tr.met = c.deviation.max <= tr.absolute;
    if (!tr.met)
      warn("subd2nurbs: warning: tolerance NOT met: deviation " + short_number(c.deviation.max) +
           " > tolerance " + short_number(tr.absolute) + " (model units) at level " +
           std::to_string(c.build.info.level));
  }
  const PatchBuildInfo& info = c.build.info;
  if (info.sharpened_edges > 0 || info.sharpened_vertices > 0)
    warn("subd2nurbs: warning: " + std::to_string(info.sharpened_edges) + " edges and " +
         std::to_string(info.sharpened_vertices) +
         " vertices were still semi-sharp at the level cap (level " + std::to_string(info.level) +
         ") and were made infinitely sharp");

  // Measures.
  t = Clock::now();
  progress.stage("measuring continuity");
  c.continuity = measure_continuity(c.build.set, kContinuitySamples);
  c.ms.continuity = ms_since(t);
  if (!options.tolerance_given) measure_deviation_now();
  collect_fans(c);

  // Output.
  if (c.kind == OutputKind::Json) {
    t = Clock::now();
    progress.stage("writing " + options.output);
    write_patch_json(options.output, c.build.set);
    c.ms.write = ms_since(t);
  } else {
    t = Clock::now();
    progress.stage("building the B-rep");
    try {
      c.brep = occt::build_brep(c.build.set, progress.percent("building the B-rep"));
    } catch (...) {
      progress.done();
      throw;
    }
    progress.done();
    c.has_brep = true;
    c.ms.brep = ms_since(t);
    if (!c.brep.valid) {
      std::string message = c.brep.check_message;
      while (!message.empty() && message.back() == '\n') message.pop_back();
      throw occt::ExportError("check", -1, "the B-rep is not valid, nothing was written:\n" + message);
    }
    t = Clock::now();
    progress.stage("writing " + options.output);
    const occt::Format format = c.kind == OutputKind::Step   ? occt::Format::Step
                                : c.kind == OutputKind::Iges ? occt::Format::Iges
                                                             : occt::Format::Brep;
    occt::write_shape(c.brep.shape, options.output, format, c.schema);
    c.ms.write = ms_since(t);
  }

  if (!options.report.empty()) {
    const std::string text = report_json(c);
    write_file_atomically(options.report, [&](std::ostream& out) { out << text; });
  }
  if (!options.quiet) print_summary(err, c);
}

}  // namespace subd2nurbs::cli
