// Two-sided distance between a cage's exact limit surface and a target shape (or a set of
// points): the independent check of fit_to_shape (core/fit/shape_fit.h). It uses the exact
// LimitEvaluator and the target's own closest-point queries, never the solver's sample rows.
//
//  * limit -> target: a grid x grid LimitEvaluator grid per ptex face (u, v at the cell centres
//    and the edges: (i + 0.5) / grid), each point's exact closest point on the target's triangles
//    (the nearest point of a point cloud);
//  * target -> limit: every target point's closest limit point: the nearest point of a dense
//    grid (grid x grid per ptex face, corners included), then Gauss-Newton projection in that
//    ptex face's (u, v) chart with the exact derivatives, clamped to [0,1]^2. A point whose foot
//    lies across the face's border is measured to the border (an upper bound, which the dense
//    start makes tight).
// All distances are relative to `diagonal` (the target's bounding-box diagonal by default).
#pragma once

#include <vector>

#include "core/fit/shape_target.h"
#include "core/limit/limit_evaluator.h"

namespace subd2nurbs {

struct DistanceStats {
  double max = 0, rms = 0, p95 = 0;  ///< relative to the diagonal
  int count = 0;
  int where_ptex = -1;               ///< the worst point's ptex face (limit side)
  double where_u = 0, where_v = 0;   ///< and its (u, v)
  int where_target = -1;             ///< the worst point's target element (triangle or point)
};

struct TargetDistance {
  DistanceStats limit_to_target, target_to_limit;
  double diagonal = 0;  ///< model units
};

/// Both directions between `limit` (holes skipped) and `target`.
TargetDistance measure_target_distance(const LimitEvaluator& limit, const ShapeTarget& target, int grid = 8);

/// Distances of `points` to their closest points on the limit surface (where_target: the point's
/// index), relative to `diagonal`.
DistanceStats points_to_limit(const LimitEvaluator& limit, const std::vector<Point3>& points, double diagonal,
                              int grid = 8);

}  // namespace subd2nurbs
