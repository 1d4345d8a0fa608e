// One step of the closest point on a surface patch to a point, in the patch's unit square.
#pragma once

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <optional>

namespace subd2nurbs {

/// The Gauss-Newton step for min |S(u, v) - q| over [0, 1]^2: r = S(u, v) - q, du and dv the
/// derivatives of S there. The next (u, v), clamped to the square, or nothing when the step is
/// not finite (the derivatives are parallel or zero).
inline std::optional<std::array<double, 2>> closest_point_step(const Eigen::Vector3d& r, const Eigen::Vector3d& du,
                                                               const Eigen::Vector3d& dv, double u, double v) {
  Eigen::Matrix2d JtJ;
  JtJ << du.dot(du), du.dot(dv), du.dot(dv), dv.dot(dv);
  const Eigen::Vector2d step = JtJ.ldlt().solve(-Eigen::Vector2d(du.dot(r), dv.dot(r)));
  if (!step.allFinite()) return std::nullopt;
  return std::array<double, 2>{std::clamp(u + step[0], 0.0, 1.0), std::clamp(v + step[1], 0.0, 1.0)};
}

}  // namespace subd2nurbs
