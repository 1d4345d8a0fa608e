#include "converter/pipeline/shape_fit_report.h"

#include <chrono>
#include <cmath>
#include <utility>

#include "converter/pipeline/settings_error.h"
#include "converter/pipeline/text.h"
#include "core/limit/limit_evaluator.h"
#include "io/input_error.h"

namespace subd2nurbs::pipeline {

namespace {

double ms_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

void write_stats(JsonWriter& w, const DistanceStats& s) {
  w.begin_object();
  w.members("max", s.max, "rms", s.rms, "p95", s.p95, "count", s.count);
  w.key("where").begin_object();
  w.members("ptex", s.where_ptex, "u", s.where_u, "v", s.where_v, "target", s.where_target);
  w.end_object().end_object();
}

}  // namespace

void validate_shape_fit(const ShapeFitOptions& o) {
  if (!(o.smoothing >= 0 && std::isfinite(o.smoothing))) throw SettingsError("smoothing", "must be a number >= 0");
  if (o.levels < 1 || o.levels > 4) throw SettingsError("levels", "must be 1 .. 4");
  if (o.max_iterations < 1) throw SettingsError("max_iterations", "must be at least 1");
  if (!(o.tolerance > 0 && std::isfinite(o.tolerance))) throw SettingsError("tolerance", "must be a positive number");
  if (!(o.min_gain >= 0 && std::isfinite(o.min_gain))) throw SettingsError("min_gain", "must be a number >= 0");
}

ShapeTarget make_target(TargetShape shape, const std::string& name) {
  for (const Point3& p : shape.points)
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
      throw InputError(name, 0, "the target has a coordinate that is not finite");
  const int n = static_cast<int>(shape.points.size());
  if (n == 0) throw InputError(name, 0, "the target has no points");
  for (const auto& t : shape.triangles)
    for (const int v : t)
      if (v < 0 || v >= n) throw InputError(name, 0, "a target triangle's vertex index is out of range");
  ShapeTarget target(std::move(shape.points), std::move(shape.triangles));
  if (!(target.diagonal() > 0)) throw InputError(name, 0, "the target has no extent (all its points coincide)");
  return target;
}

ShapeFitRun run_shape_fit(const SubdivLevel& cage, const std::vector<Point3>& start, const ShapeTarget& target,
                          const ShapeFitOptions& options, const ShapeFitProgress& progress,
                          const ShapeFitAdjust& adjust) {
  validate_shape_fit(options);
  ShapeFitRun run;
  auto t = std::chrono::steady_clock::now();
  run.before = measure_target_distance(LimitEvaluator(cage, start), target);
  run.measure_ms = ms_since(t);
  t = std::chrono::steady_clock::now();
  run.fit = fit_to_shape(cage, start, target, options, progress);
  run.fit_ms = ms_since(t);
  t = std::chrono::steady_clock::now();
  if (adjust && run.fit.stop != ShapeFitStop::Cancelled) adjust(run.fit.positions);
  run.after = measure_target_distance(LimitEvaluator(cage, run.fit.positions), target);
  run.measure_ms += ms_since(t);
  return run;
}

void write_target_distance(JsonWriter& w, const TargetDistance& d) {
  w.begin_object(4, 2);
  w.member("diagonal", d.diagonal);
  write_stats(w.key("limit_to_target"), d.limit_to_target);
  write_stats(w.key("target_to_limit"), d.target_to_limit);
  w.end_object();
}

std::string shape_fit_report_json(const ShapeFitRun& run, const ShapeFitOptions& o, const std::string& input,
                                  const std::string& target, const std::string& output) {
  JsonWriter w(JsonWriter::Numbers::Report, JsonWriter::Spacing::Spaced, "fit report");
  w.begin_object(2);
  w.members("format", "subd2nurbs-fit", "version", 1, "input", input, "target", target, "output", output);
  w.key("options").begin_object();
  w.members("smoothing", o.smoothing, "levels", o.levels, "max_iterations", o.max_iterations, "tolerance",
            o.tolerance, "min_gain", o.min_gain, "crease_angle", o.crease_angle);
  w.end_object();
  w.members("iterations", run.fit.iterations, "stop", to_string(run.fit.stop), "samples", run.fit.samples);
  if (run.tagged_edges >= 0) w.member("tagged_edges", run.tagged_edges);
  write_target_distance(w.key("before"), run.before);
  write_target_distance(w.key("after"), run.after);
  w.key("history").begin_array(4, 2);
  for (const ShapeFitIteration& h : run.fit.history) {
    w.begin_object();
    w.members("objective", h.objective, "surface_rms", h.surface_rms, "surface_max", h.surface_max, "target_rms",
              h.target_rms, "target_max", h.target_max, "point_to_plane", h.point_to_plane);
    w.end_object();
  }
  w.end_array();
  w.members("fit_ms", run.fit_ms, "measure_ms", run.measure_ms);
  w.end_object();
  return w.take() + "\n";
}

std::string distance_text(const DistanceStats& s) {
  return "max " + short_number(s.max) + ", rms " + short_number(s.rms) + ", p95 " + short_number(s.p95);
}

}  // namespace subd2nurbs::pipeline
