#include "converter/cli/convert.h"
#include "converter/cli/quality_text.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <optional>
#include <stdexcept>
#include <vector>

#include "converter/cli/commands.h"
#include "converter/occt/export_error.h"
#include "converter/occt/writers.h"
#include "converter/pipeline/conversion.h"
#include "converter/pipeline/report.h"
#include "converter/pipeline/shape_fit_report.h"
#include "core/util/parallel.h"
#include "io/atomic_file.h"
#include "io/input_error.h"
#include "io/obj_reader.h"
#include "io/obj_writer.h"
#include "io/patch_json.h"

#include <unistd.h>

namespace subd2nurbs::cli {

namespace {

/// Test hook of the signal test (tests/hostile/run_hostile.py --command signal): with
/// SUBD2NURBS_TEST_STOP=STAGE in the environment, the run prints "subd2nurbs: test stop: STAGE"
/// on stderr when it reaches STAGE and waits there (at most 60 s) for the test's signal, so that
/// the signal arrives at a known stage whatever the machine's load. Stages: "output" (the main
/// output staged, the report not yet), "commit" (every output staged, none renamed yet).
void test_stop(const char* stage, std::ostream& err) {
  const char* wanted = std::getenv("SUBD2NURBS_TEST_STOP");
  if (!wanted || std::strcmp(wanted, stage) != 0) return;
  err << "subd2nurbs: test stop: " << stage << std::endl;
  for (int second = 0; second < 60; ++second) ::sleep(1);
}

using pipeline::ApproximateFan;
using pipeline::ConversionResult;
using pipeline::short_number;

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
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

void print_summary(std::ostream& err, const ConversionResult& c, OutputKind kind, occt::StepSchema schema) {
  const PatchBuildInfo& info = c.build.info;
  const PatchSet& ps = c.build.set;
  const double size = ps.model_size > 0 ? ps.model_size : 1;
  err << "subd2nurbs: wrote " << c.output.path << " (" << output_kind_name(kind);
  if (kind == OutputKind::Step) err << " " << occt::to_string(schema);
  err << ")\n";
  err << "  patches    " << ps.patches.size() << " (" << info.regular_patches << " regular, "
      << info.pccm_patches << " pccm, " << info.caps.size() << " polar caps), " << info.total_poles
      << " poles, deepest level " << info.level
      << " (coarse level " << info.coarse_level << ", " << c.extra_levels << " extra)\n";
  const PackedSet& out = c.exported;
  err << "  faces      " << out.set.patches.size() << " (" << pipeline::to_string(c.faces) << ": " << out.packs
      << " packs of " << out.packed_quads << " quads), " << out.total_poles << " poles\n";
  if (!c.caps.empty()) {
    double dist = 0, angle = 0, k_near = 0, k_far = 0;
    for (const pipeline::CapMeasure& m : c.caps) {
      dist = std::max(dist, m.bp_distance);
      angle = std::max(angle, m.pole.normal_angle_deg[1]);
      k_far = std::max(k_far, m.pole.max_abs_k[0]);
      k_near = std::max(k_near, m.pole.max_abs_k[1]);
    }
    err << "  polar      " << c.caps.size() << " caps (" << c.cap_options.radial_steps << " radial pre-step"
        << (c.cap_options.radial_steps > 1 ? "s" : "") << ", lambda " << short_number(c.cap_options.lambda)
        << "): max distance from the BP limit " << short_number(dist) << " (" << short_number(dist / size)
        << " of the model size); normal at the pole within " << short_number(angle)
        << " deg of BP's; max |k| " << short_number(k_far) << " at 1e-2 and " << short_number(k_near)
        << " at 1e-4 from the pole\n";
  }
  const auto& fm = c.fans_by_mode;
  err << "  fans       " << fm[0] << " smooth, " << fm[1] << " dart, " << fm[2] << " crease, " << fm[3]
      << " corner, " << fm[4] << " approximate\n";
  if (c.has_brep)
    err << "  B-rep      " << (c.brep.is_solid ? "solid" : "shell") << ", " << c.brep.num_faces << " faces, "
        << c.brep.num_edges << " edges, " << c.brep.num_vertices << " vertices, "
        << (c.brep.valid ? "valid" : "NOT valid") << "\n";
  if (c.has_brep && c.brep.planar_faces > 0)
    err << "  planes     " << c.brep.planar_faces << " planar faces in place of " << c.brep.merged_patches
        << " coplanar faces"
        << (c.brep.folded_planar_patches > 0 ? " (" + std::to_string(c.brep.folded_planar_patches) + " of them folded in their plane)" : std::string())
        << "\n";
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
  if (c.fit.mode == pipeline::FitMode::Interpolate) {
    const pipeline::FitReport& f = c.fit;
    err << "  fit        interpolate" << (f.fair_weight > 0 ? " (fair, weight " + short_number(f.fair_weight) + ")" : "")
        << ": residual max " << short_number(f.residual.max) << " (" << short_number(f.residual.max / size)
        << " of the model size) at vertex " << f.residual.where << ", mean " << short_number(f.residual.mean)
        << "; cage moved max " << short_number(f.displacement.max) << " at vertex " << f.displacement.where
        << ", mean " << short_number(f.displacement.mean);
    if (f.fair_weight > 0)
      err << "; energy " << short_number(f.energy_before) << " -> " << short_number(f.energy_after);
    else
      err << "; condition ~" << short_number(f.condition) << (f.singular ? " (singular)" : "");
    err << "\n";
  }
  if (c.tolerance_given)
    err << "  tolerance  " << short_number(c.tolerance.absolute) << " (model units"
        << (c.tolerance.is_default ? ", the default 1e-4 of the model size" : "") << "): "
        << (c.tolerance.met ? "met" : "NOT met") << "; " << c.tolerance.fans_deepened
        << " vertices' fans deepened, by up to " << c.tolerance.used << " levels\n";
  err << "  estimate   peak memory " << pipeline::bytes_text(c.estimate.bytes) << ", "
      << pipeline::time_class(c.estimate.seconds) << " of CPU time (before any work: "
      << pipeline::bytes_text(c.estimate_before.bytes) << ", " << pipeline::time_class(c.estimate_before.seconds)
      << ")\n";
}

/// The settings of `options`, checked by the pipeline's rules before any work: the table's
/// options as given; the B-rep unless the output is patch JSON; the quality stage for --report;
/// a preview (curvature unless --color says otherwise) only with --preview.
pipeline::Settings conversion_settings(const ConvertOptions& options, bool build_brep) {
  SettingValues given = options.settings;
  given.emplace_back("brep", build_brep);
  pipeline::Settings settings = pipeline::make_settings(given);
  if (!options.report.empty()) settings.conversion.quality_samples = pipeline::kReportQualitySamples;
  if (options.preview.empty()) settings.preview.reset();
  else if (!settings.preview) settings.preview = PreviewColor::Curvature;
  return settings;
}

/// `--fit-to`: the cage's positions fitted to the target shape with the default options (the
/// same fit as `subd2nurbs fit`), the distances before and after on stderr.
pipeline::ShapeFitRun fit_to_target(const ConvertOptions& options, const pipeline::Settings& settings,
                                    const SubdivLevel& base, const std::vector<Point3>& positions, Progress& progress,
                                    std::ostream& err) {
  if (settings.conversion.fit.mode != pipeline::FitMode::Approximate)
    throw UsageError("--fit-to and --fit interpolate exclude each other: the fit to a target already decides the cage");
  const ShapeTarget target = pipeline::make_target(read_target(options.fit_to), options.fit_to);
  progress.stage("fitting the cage to " + options.fit_to);
  const pipeline::ShapeFitRun run = pipeline::run_shape_fit(base, positions, target, ShapeFitOptions{});
  if (!options.quiet) {
    err << "subd2nurbs: fitted in " << run.fit.iterations << " iterations, stopped: " << to_string(run.fit.stop) << "\n";
    print_target_distance(err, "subd2nurbs: before", run.before);
    print_target_distance(err, "subd2nurbs: after", run.after);
  }
  return run;
}

}  // namespace

// --- the subcommand ------------------------------------------------------------------------

void run_convert(const ConvertOptions& options, std::ostream& err) {
  const OutputKind kind = output_kind(options.output);
  const pipeline::Settings all = conversion_settings(options, kind != OutputKind::Json);
  const occt::StepSchema schema = all.write.schema;
  const pipeline::ConversionSettings settings = pipeline::conversion_settings(all);
  // --threads for everything below: the mesh path, the fit to a target and the conversion.
  const ThreadLimit threads(settings.limits.threads.value_or(0));
  check_outputs(options.mesh, {{"-o", options.output}, {"--report", options.report}, {"--preview", options.preview},
                               {"--keep-cage", options.keep_cage}});
  if (!options.fit_to.empty())
    for (const std::string& out : {options.output, options.report, options.preview, options.keep_cage})
      if (!out.empty() && same_file(options.fit_to, out))
        throw UsageError("an output is the target file " + printable(options.fit_to) + "; choose another output name");

  Progress progress(err, options.quiet, options.progress_tty);
  std::vector<std::string> load_warnings;
  auto warn = [&](const std::string& w) {
    err << w << "\n";
    load_warnings.push_back(w);
  };

  // Load: a cage, or a mesh made into a fitted cage (the mesh path, pipeline/mesh_path.h).
  auto t = Clock::now();
  progress.stage("reading " + options.mesh);
  pipeline::LoadedSource source = pipeline::load_source(options.mesh, all.mesh.input, usd_read_options());
  std::optional<pipeline::MeshCage> made;
  if (source.route.mesh) {
    for (const std::string& w : source.warnings) warn(w);
    if (!options.fit_to.empty())
      throw UsageError("--fit-to fits a cage; " + options.mesh + " is taken as a mesh (" + source.route.reason +
                       "), which is fitted to itself: drop --fit-to, or give --input cage");
    progress.stage(options.mesh + ": " + source.route.reason);
    pipeline::MeshPathProgress mesh_progress;
    mesh_progress.stage = [&](const std::string& what) { progress.stage(what); };
    made = pipeline::mesh_to_cage(source.mesh, all.mesh, mesh_progress);
    made->report.route = source.route;
    for (const std::string& w : made->report.warnings) warn(w);
    source.cage = std::move(made->cage);
  }
  const LoadedInput& loaded = *source.cage;
  const LoadedCage& cage = loaded.cage;
  const SubdivLevel& base = loaded.level;
  if (!made)
    for (const std::string& w : loaded.warnings) warn(w);
  std::vector<Point3> positions = made ? made->positions : loaded.positions();
  const double load_ms = ms_since(t);
  std::optional<pipeline::FitReport::ToTarget> to_target;
  if (!options.fit_to.empty()) {
    pipeline::ShapeFitRun run = fit_to_target(options, all, base, positions, progress, err);
    positions = std::move(run.fit.positions);
    to_target = pipeline::FitReport::ToTarget{options.fit_to, run.fit.iterations, to_string(run.fit.stop), run.before, run.after};
  }
  if (cage.recovery.applied && !options.quiet)
    err << "subd2nurbs: recovered " << cage.recovery.quads << " quads from " << cage.recovery.source_triangles
        << " triangles (" << cage.recovery.triangles_kept << " triangles kept, " << cage.recovery.fan_vertices
        << " fan vertices)\n";

  // Patches, measures and (unless the output is patch JSON) the B-rep.
  pipeline::ConversionProgress callbacks;
  std::function<void(double)> brep_percent;  // started with the B-rep stage (percent() times it)
  callbacks.stage = [&](pipeline::Stage stage, const std::string& what) {
    progress.stage(what);
    if (stage == pipeline::Stage::Brep) brep_percent = progress.percent(what);
  };
  callbacks.brep_fraction = [&](double fraction) {
    if (brep_percent) brep_percent(fraction);
  };
  DiagnosticPrinter diagnostics(err, options.quiet);
  callbacks.diagnostic = std::ref(diagnostics);
  // Outputs: all staged in temporary files first, renamed over their names only when every
  // one of them is ready. The output file is staged as soon as the B-rep is built, while the
  // quality stage (--report) still runs beside it.
  std::vector<StagedFile> staged;
  callbacks.after_brep = [&](ConversionResult& r) {
    if (kind == OutputKind::Json) {
      const auto t0 = Clock::now();
      progress.stage("writing " + options.output);
      const std::string text = patch_set_to_json(r.exported.set);
      staged.emplace_back(options.output);
      staged.back().write([&](std::ostream& out) { out << text; });
      r.ms.write = ms_since(t0);
      return;
    }
    if (!r.brep.valid) {
      std::string message = r.brep.check_message;
      while (!message.empty() && message.back() == '\n') message.pop_back();
      throw occt::ExportError("check", -1, "the B-rep is not valid, nothing was written:\n" + message);
    }
    const auto t0 = Clock::now();
    progress.stage("writing " + options.output);
    const occt::Format format = kind == OutputKind::Step   ? occt::Format::Step
                                : kind == OutputKind::Iges ? occt::Format::Iges
                                                           : occt::Format::Brep;
    pipeline::check_exchange_output(r, options.mesh, format != occt::Format::Brep);
    staged.push_back(occt::stage_shape(r.brep.shape, options.output, format, schema));
    r.ms.write = ms_since(t0);
    test_stop("output", err);
  };
  ConversionResult c;
  try {
    c = pipeline::convert(base, positions, settings, callbacks, std::move(load_warnings));
  } catch (...) {
    progress.done();
    throw;
  }
  progress.done();
  diagnostics.finish();
  c.input = options.mesh;
  c.output.path = options.output;
  c.output.format = output_kind_name(kind);
  if (kind == OutputKind::Step) c.output.step_schema = occt::to_string(schema);
  c.ms.load = load_ms;
  if (made) c.mesh = std::move(made->report);
  c.fit.to_target = std::move(to_target);

  if (!options.report.empty()) {
    if (!options.quiet) print_quality_summary(err, *c.quality, c.build.set.model_size);
    const std::string text = pipeline::report_json(c);
    staged.emplace_back(options.report);
    staged.back().write([&](std::ostream& out) { out << text; });
  }
  if (!options.preview.empty()) staged.push_back(stage_preview(options, c, err));
  if (!options.keep_cage.empty()) {
    staged.emplace_back(options.keep_cage);
    staged.back().write([&](std::ostream& out) { write_obj(out, c.cage, base); });
  }
  test_stop("commit", err);
  for (StagedFile& file : staged) file.commit();
  if (!options.quiet) {
    if (c.mesh) err << pipeline::mesh_path_summary(*c.mesh);
    print_summary(err, c, kind, schema);
  }
}

}  // namespace subd2nurbs::cli
