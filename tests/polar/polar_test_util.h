// Helpers for the polar tests: Eigen conversions, curvature from derivatives, the uniform
// bicubic spline of a polar net's (ring, spoke) grid, and the distance from the BP limit
// surface to a cap.
#pragma once

#include <algorithm>
#include <cmath>

#include <Eigen/Core>
#include <Eigen/Dense>
#include <Eigen/Geometry>

#include "core/nurbs/nurbs_eval.h"
#include "core/limit/limit_evaluator.h"  // sample_from_derivatives
#include "core/polar/polar_cap.h"
#include "core/polar/polar_net.h"

namespace subd2nurbs::testing {

using V3 = Eigen::Vector3d;
inline V3 ev(const Point3& p) { return {p[0], p[1], p[2]}; }
inline Point3 pt(const V3& v) { return {v.x(), v.y(), v.z()}; }

inline double angle_deg(const V3& a, const V3& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / M_PI;
}

inline V3 unit(const SurfaceDerivs& d) { return ev(d.du).cross(ev(d.dv)).normalized(); }

struct Curvature {
  double k1 = 0, k2 = 0;  ///< principal curvatures, k1 >= k2
  V3 normal;
};

/// Principal curvatures from the derivatives (the fundamental forms, core/limit).
inline Curvature curvature(const SurfaceDerivs& d) {
  const LimitSample s = sample_from_derivatives(d);
  return {s.k1, s.k2, ev(s.normal)};
}

/// The patch with every pole moved by -centre: evaluating relative to the cap's centre
/// keeps the derivatives' digits near the pole (MATH.md 4).
inline NurbsPatch relative_to_centre(NurbsPatch p, const Point3& centre) {
  for (Point3& q : p.poles) q = pt(ev(q) - ev(centre));
  return p;
}

/// The uniform bicubic B-spline of a polar net's grid, ring r centred at U = r and spoke j
/// at V = j (periodic). Valid where the four rings it reads exist (1 <= U - 1, U + 2 <= R).
inline V3 grid_point(const PolarNet& net, double U, double V) {
  auto basis = [](double t, double w[4]) {
    const double s = 1 - t;
    w[0] = s * s * s / 6;
    w[1] = (3 * t * t * t - 6 * t * t + 4) / 6;
    w[2] = (-3 * t * t * t + 3 * t * t + 3 * t + 1) / 6;
    w[3] = t * t * t / 6;
  };
  const int i = std::min(static_cast<int>(std::floor(U)), net.num_rings() - 2);
  const int j = static_cast<int>(std::floor(V));
  double wu[4], wv[4];
  basis(U - i, wu);
  basis(V - j, wv);
  V3 s = V3::Zero();
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b) s += wu[a] * wv[b] * ev(net.at(i - 1 + a, j - 1 + b));
  return s;
}

}  // namespace subd2nurbs::testing
