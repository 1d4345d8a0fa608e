// Helpers for the polar tests: Eigen conversions, curvature from derivatives, the uniform
// bicubic spline of a polar net's (ring, spoke) grid, and the distance from the BP limit
// surface to a cap.
#pragma once

#include <algorithm>
#include <cmath>

#include <Eigen/Core>
#include <Eigen/Dense>
#include <Eigen/Geometry>

#include "core/eval/nurbs_eval.h"
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

/// Principal curvatures from the first and second fundamental forms.
inline Curvature curvature(const SurfaceDerivs& d) {
  const V3 xu = ev(d.du), xv = ev(d.dv);
  Curvature c;
  c.normal = xu.cross(xv).normalized();
  const double E = xu.dot(xu), F = xu.dot(xv), G = xv.dot(xv);
  const double L = ev(d.duu).dot(c.normal), M = ev(d.duv).dot(c.normal), N = ev(d.dvv).dot(c.normal);
  const double det = E * G - F * F;
  const double K = (L * N - M * M) / det, H = (E * N - 2 * F * M + G * L) / (2 * det);
  const double root = std::sqrt(std::max(0.0, H * H - K));
  c.k1 = H + root;
  c.k2 = H - root;
  return c;
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

/// Closest point of a cap patch to x, by damped Gauss-Newton (Levenberg-Marquardt) from
/// (u, v), started a little away from the collapsed edge u = 0 where x_v vanishes; returns
/// the distance.
inline double distance_to_patch(const NurbsPatch& patch, const V3& x, double u, double v) {
  u = std::max(u, 0.02);
  double best = (x - ev(evaluate(patch, u, v).p)).norm(), mu = 1e-3;
  for (int it = 0; it < 100 && best > 0; ++it) {
    const SurfaceDerivs d = evaluate(patch, u, v);
    const V3 r = x - ev(d.p), xu = ev(d.du), xv = ev(d.dv);
    Eigen::Matrix2d A;
    A << xu.dot(xu), xu.dot(xv), xu.dot(xv), xv.dot(xv);
    const Eigen::Vector2d b(xu.dot(r), xv.dot(r));
    Eigen::Matrix2d D = A;
    D(0, 0) *= 1 + mu;
    D(1, 1) *= 1 + mu;
    D += 1e-30 * Eigen::Matrix2d::Identity();
    const Eigen::Vector2d step = D.ldlt().solve(b);
    if (!step.allFinite()) break;
    const double un = std::clamp(u + step[0], 0.0, 1.0);
    double vn = v + step[1];
    vn -= std::floor(vn);
    const double dist = (x - ev(evaluate(patch, un, vn).p)).norm();
    if (dist < best) {
      best = dist;
      u = un;
      v = vn;
      mu = std::max(mu / 4, 1e-12);
      if (step.norm() < 1e-14) break;
    } else {
      mu *= 8;
      if (mu > 1e12) break;
    }
  }
  return best;
}

/// Largest distance from the BP limit surface of rings 0..3 (limit points of the grid after
/// `levels` radial steps, from ring 3 out to the cap's boundary, and the pole's limit point)
/// to the cap built with `radial_steps` pre-steps.
inline double distance_bp_to_cap(const PolarNet& rings0to3, const PolarCap& cap, const NurbsPatch& patch,
                                 int levels) {
  PolarNet p = rings0to3;
  p.rings.resize(static_cast<size_t>(3) * p.n);
  for (int l = 0; l < levels; ++l) p = radial_step(p);
  const int s = static_cast<int>(std::lround(std::log2((cap.m + 2 + 1) / 4.0)));  // m = 2^(s+1) - 1
  double worst = (ev(bp_limit_point(rings0to3)) - ev(cap.centre)).norm();
  const int last = 1 << (levels + 1);  // input ring 2, the cap's boundary
  for (int r = 3; r <= last && r + 1 <= p.num_rings(); ++r)
    for (int j = 0; j < p.n; ++j) {
      const double U = static_cast<double>(r) / (1 << levels);
      const double u = std::clamp(((1 << s) * U - 1) / cap.m, 0.0, 1.0);
      worst = std::max(worst, distance_to_patch(patch, ev(bp_grid_limit(p, r, j)), u, static_cast<double>(j) / p.n));
    }
  return worst;
}

}  // namespace subd2nurbs::testing
