// Fitting a cage to a target shape for the front ends (`subd2nurbs fit`, Python fit(); the core
// is core/fit/shape_fit.h): the option rules, the fit with the independent two-sided measure
// (core/eval/target_distance.h) of the input cage and of the fitted one, and its JSON report
// (subd2nurbs-fit v1, docs/formats.md). The two-sided distance's JSON is also check's "target".
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "core/eval/target_distance.h"
#include "core/fit/shape_fit.h"
#include "core/refine/refiner.h"
#include "io/json_writer.h"
#include "io/target_reader.h"

namespace subd2nurbs::pipeline {

/// The rules of a shape fit's options: smoothing >= 0, levels 1 .. 4, max_iterations >= 1,
/// tolerance > 0. \throw SettingsError ("smoothing", "levels", "max_iterations", "tolerance")
void validate_shape_fit(const ShapeFitOptions& options);

/// The target for fit_to_shape and the measure. \throw InputError naming `name` (the target
/// is degenerate: no extent)
ShapeTarget make_target(TargetShape shape, const std::string& name);

struct ShapeFitRun {
  ShapeFitResult fit;
  TargetDistance before, after;  ///< the input cage's and the fitted cage's limit to the target
  double fit_ms = 0, measure_ms = 0;
  int tagged_edges = -1;         ///< cage edges tagged along the target's features (-1: not asked)
};

/// Changes the fitted positions before they are measured (the mesh path's planar flattening).
using ShapeFitAdjust = std::function<void(std::vector<Point3>& positions)>;

/// Validates the options, fits `cage` from `start` to `target`, applies `adjust` (if any) to the
/// fitted positions, and measures both cages. \throw SettingsError, FitError
ShapeFitRun run_shape_fit(const SubdivLevel& cage, const std::vector<Point3>& start, const ShapeTarget& target,
                          const ShapeFitOptions& options, const ShapeFitProgress& progress = {},
                          const ShapeFitAdjust& adjust = {});

/// The two-sided distance as a JSON object: diagonal, limit_to_target and target_to_limit, each
/// max / rms / p95 (relative to the diagonal), count and where {ptex, u, v, target}.
void write_target_distance(JsonWriter& w, const TargetDistance& d);

/// The fit report (subd2nurbs-fit v1), ending in a newline.
std::string shape_fit_report_json(const ShapeFitRun& run, const ShapeFitOptions& options, const std::string& input,
                                  const std::string& target, const std::string& output);

/// "max M, rms R, p95 P" of one direction, for the stderr summaries.
std::string distance_text(const DistanceStats& s);

}  // namespace subd2nurbs::pipeline
