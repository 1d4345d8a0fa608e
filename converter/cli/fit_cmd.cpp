#include "converter/cli/fit_cmd.h"

#include <CLI/CLI.hpp>

#include <optional>

#include "converter/cli/commands.h"
#include "converter/cli/quality_text.h"
#include "converter/pipeline/shape_fit_report.h"
#include "converter/pipeline/text.h"
#include "io/atomic_file.h"
#include "io/input_file.h"
#include "io/obj_writer.h"
#include "io/target_reader.h"

namespace subd2nurbs::cli {

CLI::App* add_fit_command(CLI::App& app, FitCommandOptions& o) {
  CLI::App* c = add_cage_command(
      app, "fit",
      "Fit a cage to a target shape (a triangle mesh, or a point cloud: PLY or OBJ with vertices only, .xyz): "
      "move its vertices so that the limit surface fits the target; write the cage as OBJ",
      o.mesh);
  c->add_option("--to", o.target, "The target: STL, PLY, OFF, OBJ, glTF (triangles) or a point cloud (.xyz, "
                                  "PLY / OBJ with vertices only)")
      ->required();
  c->add_option("-o,--output", o.output, "Output OBJ file (same topology and tags)")->required();
  c->add_option("--smoothing", o.smoothing, "Weight of the thin-plate energy (>= 0, default 1e-4)");
  c->add_option("--levels", o.levels, "Refinement levels of the surface samples (1..4, default 3)");
  c->add_option("--max-iterations", o.max_iterations, "Closest-point iterations at most (>= 1, default 30)");
  c->add_option("--tolerance", o.tolerance,
                "Stop when both RMS distances are at most T x the target's diagonal (> 0, default 1e-7)");
  c->add_option("--min-gain", o.min_gain,
                "Stop when an iteration improves the two-sided RMS distance by less than this fraction (>= 0, "
                "0: off, default 0.02)");
  c->add_flag("--exact-target", o.exact_target,
              "The target lies on a subdivision surface (a dense sampling of one, no noise): weights that recover "
              "it (target -> surface 30, surface -> target 1e-3 in the last phase, crease curves onto the target's "
              "sharp edges; smoothing 0, tolerance 1e-8, 100 iterations unless given)");
  c->add_flag("--tag-features", o.tag_features,
              "Before fitting, tag the cage edges that lie along the target's sharp edges (faces meeting at more "
              "than 30 degrees) infinitely sharp (for a cage drawn on the shape, e.g. a remesh)");
  c->add_option("--report", o.report, "Also write a JSON report (iterations, distances before and after)");
  c->add_flag("--register", o.register_first,
              "First move, scale and rotate the cage onto the target (a similarity: for a target in another frame or "
              "scale)");
  c->add_flag("-q,--quiet", o.quiet, "No progress or summary on stderr (warnings are still printed)");
  return c;
}

void run_fit(const FitCommandOptions& o, std::ostream& err) {
  ShapeFitOptions fo = o.exact_target ? exact_target_options() : ShapeFitOptions{};
  if (o.smoothing) fo.smoothing = *o.smoothing;
  fo.levels = o.levels;
  if (o.max_iterations) fo.max_iterations = *o.max_iterations;
  if (o.tolerance) fo.tolerance = *o.tolerance;
  fo.min_gain = o.min_gain;
  pipeline::validate_shape_fit(fo);
  check_outputs(o.mesh, {{"-o", o.output}, {"--report", o.report}});
  if (same_file(o.target, o.output) || (!o.report.empty() && same_file(o.target, o.report)))
    throw UsageError("an output is the target file " + printable(o.target) + "; choose another output name");
  const LoadedInput loaded = load_input(o.mesh);
  for (const std::string& w : loaded.warnings) err << w << "\n";
  const ShapeTarget target = pipeline::make_target(read_target(o.target), o.target);
  if (!o.quiet)
    err << "subd2nurbs: fitting " << o.mesh << " (" << loaded.level.mesh.num_vertices() << " vertices) to "
        << o.target << " (" << target.points().size()
        << (target.has_triangles() ? " points, " + std::to_string(target.triangles().size()) + " triangles)"
                                   : std::string(" points)"))
        << "\n";

  ShapeFitProgress progress;
  if (!o.quiet)
    progress = [&](int iteration, double objective) {
      err << "subd2nurbs: iteration " << iteration + 1 << ": objective " << pipeline::short_number(objective) << "\n";
      return true;
    };
  std::vector<Point3> start = loaded.positions();
  if (o.register_first) {
    // The cage's limit points (level 2) registered onto the target; the similarity moves the
    // cage, whose limit it moves alike (Catmull-Clark commutes with similarities).
    std::vector<Point3> limit_points;
    shape_fit_sample_rows(loaded.level, 2).apply(start, limit_points);
    const Similarity sim = register_to_target(limit_points, target);
    for (Point3& p : start) p = sim.apply(p);
    if (!o.quiet)
      err << "subd2nurbs: registered: scale " << pipeline::short_number(sim.scale) << ", translation ("
          << pipeline::short_number(sim.t[0]) << ", " << pipeline::short_number(sim.t[1]) << ", "
          << pipeline::short_number(sim.t[2]) << "), rms distance " << pipeline::short_number(sim.rms)
          << " of the target's diagonal\n";
  }
  SubdivLevel level = loaded.level;
  int tagged = -1;
  if (o.tag_features) {
    // The cage's edges along the target's feature curves, creased. The crease term (crease
    // curves fitted to the target's feature vertices) stays off: on fandisk it left the largest
    // distance at 0.56 % of the diagonal against 0.37 % without it (docs/benchmarks.md 9).
    constexpr double kFeatureAngle = 30.0;
    const std::vector<int> edges = feature_edges_on_target(level, start, target, kFeatureAngle);
    for (int e : edges) level.edge_sharpness[e] = static_cast<float>(kInfiniteSharpness);
    tagged = static_cast<int>(edges.size());
    if (!o.quiet) err << "subd2nurbs: tagged " << tagged << " cage edges along the target's sharp edges\n";
  }
  pipeline::ShapeFitRun run = pipeline::run_shape_fit(level, start, target, fo, progress);
  run.tagged_edges = tagged;

  // Both outputs staged, then renamed into place together.
  StagedFile obj(o.output);
  obj.write([&](std::ostream& out) { write_obj(out, run.fit.positions, level); });
  std::optional<StagedFile> report;
  if (!o.report.empty()) {
    const std::string text = pipeline::shape_fit_report_json(run, fo, o.mesh, o.target, o.output);
    report.emplace(o.report);
    report->write([&](std::ostream& out) { out << text; });
  }
  obj.commit();
  if (report) report->commit();

  if (o.quiet) return;
  err << "subd2nurbs: wrote " << o.output << ": " << run.fit.iterations << " iterations, stopped: "
      << to_string(run.fit.stop) << "\n";
  print_target_distance(err, "subd2nurbs: before", run.before);
  print_target_distance(err, "subd2nurbs: after", run.after);
}

}  // namespace subd2nurbs::cli
