#include "core/polar/polar_cap.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Core>
#include <Eigen/Dense>

#include "core/nurbs/nurbs_eval.h"
#include "core/limit/limit_evaluator.h"  // sample_from_derivatives: curvature

#include "core/util/constants.h"
#include "core/util/eigen_point.h"

namespace subd2nurbs {
namespace {

using V3 = Eigen::Vector3d;

/// Clamped knots 0 (x4), 1, ..., count-1, count (x4), divided by count.
KnotVector clamped_uniform(int count) {
  KnotVector kv;
  for (int i = 0; i <= count; ++i) {
    kv.knots.push_back(static_cast<double>(i) / count);
    kv.mults.push_back(i == 0 || i == count ? 4 : 1);
  }
  return kv;
}

}  // namespace

PolarNet polar_net_of(const PolarStructure& s, const std::vector<Point3>& positions) {
  PolarNet net;
  net.n = s.valence;
  net.pole = positions[s.pole];
  for (const auto& ring : s.rings)
    for (int v : ring) net.rings.push_back(positions[v]);
  return net;
}

PolarCap build_polar_cap(const PolarNet& input, const PolarCapOptions& options) {
  if (input.n < 3 || input.num_rings() < 3)
    throw std::invalid_argument("build_polar_cap: needs n >= 3 and rings 0..3");
  if (options.radial_steps < 1) throw std::invalid_argument("build_polar_cap: radial_steps must be >= 1");
  if (!(options.lambda > 0)) throw std::invalid_argument("build_polar_cap: lambda must be > 0");
  // (i) radial pre-subdivision of rings 0..3 only (further rings would not be valid BP rings).
  PolarNet p = input;
  p.rings.resize(static_cast<size_t>(3) * p.n);
  for (int s = 0; s < options.radial_steps; ++s) p = radial_step(p);
  const int n = p.n, R = p.num_rings();  // rows c_0..c_R
  PolarCap cap;
  cap.n = n;
  cap.m = R - 2;
  cap.radial_steps = options.radial_steps;
  // (iii) the collapsed row interpolates the BP limit point.
  cap.centre = bp_limit_point(p);
  cap.normal = bp_limit_normal(p);
  const V3 c0 = to_eigen(cap.centre);
  // (iv) c_1i = c0 + lambda (cos t_i E1 + sin t_i E2), E = (2/n) sum (cos, sin) t_j (p_1j - c0).
  V3 E1 = V3::Zero(), E2 = V3::Zero();
  for (int j = 0; j < n; ++j) {
    const double t = 2 * kPi * j / n;
    const V3 d = to_eigen(p.at(1, j)) - c0;
    E1 += std::cos(t) * d;
    E2 += std::sin(t) * d;
  }
  E1 *= 2.0 / n;
  E2 *= 2.0 / n;
  // (ii) row r = ring r.
  cap.rows.resize(static_cast<size_t>(R + 1) * n);
  for (int j = 0; j < n; ++j) {
    const double t = 2 * kPi * j / n;
    cap.rows[j] = cap.centre;
    cap.rows[static_cast<size_t>(n) + j] = to_point(c0 + options.lambda * (std::cos(t) * E1 + std::sin(t) * E2));
    for (int r = 2; r <= R; ++r) cap.rows[static_cast<size_t>(r) * n + j] = p.at(r, j);
  }
  return cap;
}

NurbsPatch polar_cap_patch(const PolarCap& cap, int circular_refinements) {
  // Circular knot insertion on every row (the periodic cubic B-spline refinement of 2.2).
  int n = cap.n;
  std::vector<Point3> rows = cap.rows;
  const int num_rows = static_cast<int>(rows.size()) / n;
  for (int s = 0; s < circular_refinements; ++s) {
    std::vector<Point3> next(static_cast<size_t>(num_rows) * 2 * n);
    for (int r = 0; r < num_rows; ++r)
      for (int i = 0; i < n; ++i) {
        auto at = [&](int j) { return to_eigen(rows[static_cast<size_t>(r) * n + (j + n) % n]); };
        next[static_cast<size_t>(r) * 2 * n + 2 * i] = to_point((at(i - 1) + 6 * at(i) + at(i + 1)) / 8);
        next[static_cast<size_t>(r) * 2 * n + 2 * i + 1] = to_point((at(i) + at(i + 1)) / 2);
      }
    rows.swap(next);
    n *= 2;
  }
  auto c = [&](int r, int j) { return to_eigen(rows[static_cast<size_t>(r) * n + (j + n) % n]); };
  // Seam clamp (docs/math.md 4.4), column j = blossom f(j-1, j, j+1): n + 3 columns per row.
  std::vector<std::vector<V3>> clamped_v(num_rows);
  for (int r = 0; r < num_rows; ++r) {
    std::vector<V3>& D = clamped_v[r];
    D.push_back((c(r, n - 1) + 4 * c(r, 0) + c(r, 1)) / 6);
    D.push_back((2 * c(r, 0) + c(r, 1)) / 3);
    for (int k = 2; k <= n; ++k) D.push_back(c(r, k - 1));
    D.push_back((c(r, n - 1) + 2 * c(r, 0)) / 3);
    D.push_back(D.front());
  }
  // Outer clamp (docs/math.md 4.1 (v), 4.4): rows c_0..c_m kept, then (c_m + 2c_{m+1})/3 and
  // (c_m + 4c_{m+1} + c_{m+2})/6.
  const int m = cap.m;
  NurbsPatch patch;
  patch.kind = PatchKind::PolarCap;
  patch.num_poles_u = m + 3;
  patch.num_poles_v = n + 3;
  patch.knots_u = clamped_uniform(m);
  patch.knots_v = clamped_uniform(n);
  patch.poles.resize(static_cast<size_t>(patch.num_poles_u) * patch.num_poles_v);
  for (int j = 0; j < patch.num_poles_v; ++j) {
    auto row = [&](int r) { return clamped_v[r][j]; };
    // u knots 0,0,0,0,1,...: row 0 = f(0,0,0), row 1 = f(0,0,1), row r >= 2 = f(r-2, r-1, r):
    // with the 4-fold start the unclamped rows already are the clamped poles up to row m.
    patch.pole(0, j) = cap.centre;  // exactly: the averages above would round it
    for (int r = 1; r <= m; ++r) patch.pole(r, j) = to_point(row(r));
    patch.pole(m + 1, j) = to_point((row(m) + 2 * row(m + 1)) / 3);
    patch.pole(m + 2, j) = to_point((row(m) + 4 * row(m + 1) + row(m + 2)) / 6);
  }
  return patch;
}

namespace {

/// Closest point of a patch to x by damped Gauss-Newton from (u, v), v periodic; started a
/// little away from u = 0, where a cap's Xv vanishes. Returns the distance.
double distance_to_patch(const PatchEvaluator& patch, const V3& x, double u, double v) {
  u = std::max(u, 0.02);
  double best = (x - to_eigen(patch.point(u, v))).norm(), mu = 1e-3;
  for (int it = 0; it < 100 && best > 0; ++it) {
    const SurfaceDerivs d = patch.derivs(u, v, 1);
    const V3 r = x - to_eigen(d.p), xu = to_eigen(d.du), xv = to_eigen(d.dv);
    Eigen::Matrix2d A;
    A << xu.dot(xu) * (1 + mu), xu.dot(xv), xu.dot(xv), xv.dot(xv) * (1 + mu);
    A += 1e-30 * Eigen::Matrix2d::Identity();
    const Eigen::Vector2d step = A.ldlt().solve(Eigen::Vector2d(xu.dot(r), xv.dot(r)));
    if (!step.allFinite()) break;
    const double un = std::clamp(u + step[0], 0.0, 1.0);
    const double vn = v + step[1] - std::floor(v + step[1]);
    const double dist = (x - to_eigen(patch.point(un, vn))).norm();
    if (dist < best) {
      best = dist;
      u = un;
      v = vn;
      mu = std::max(mu / 4, 1e-12);
      if (step.norm() < 1e-14) break;
    } else if ((mu *= 8) > 1e12) {
      break;
    }
  }
  return best;
}

}  // namespace

CapPoleMeasure measure_cap_pole(const PolarCap& cap, const NurbsPatch& patch) {
  NurbsPatch relative = patch;
  for (Point3& q : relative.poles) q = to_point(to_eigen(q) - to_eigen(cap.centre));
  const V3 bn = to_eigen(cap.normal);
  CapPoleMeasure m;
  for (int i = 0; i < 2; ++i)
    for (int q = 0; q < 64; ++q) {
      const LimitSample s = sample_from_derivatives(evaluate(relative, m.distance[i] / cap.m, (q + 0.5) / 64));
      const V3 nv = to_eigen(s.normal);
      m.normal_angle_deg[i] = std::max(m.normal_angle_deg[i], std::atan2(nv.cross(bn).norm(), nv.dot(bn)) * 180 / kPi);
      m.max_abs_k[i] = std::max({m.max_abs_k[i], std::abs(s.k1), std::abs(s.k2)});
    }
  return m;
}

double cap_distance_to_bp(const PolarNet& rings0to3, const PolarCap& cap, const NurbsPatch& patch, int levels) {
  PolarNet p = rings0to3;
  p.rings.resize(static_cast<size_t>(3) * p.n);
  for (int l = 0; l < levels; ++l) p = radial_step(p);
  double worst = (to_eigen(bp_limit_point(rings0to3)) - to_eigen(cap.centre)).norm();
  const int last = 2 << levels;  // input ring 2 = the cap's boundary
  const double scale = 1.0 / (1 << levels), pre = 1 << cap.radial_steps;
  const PatchEvaluator evaluator(patch);
  for (int r = 3; r <= last && r + 1 <= p.num_rings(); ++r)
    for (int j = 0; j < p.n; ++j) {
      // Input parameter U = r 2^-levels; the cap's u = 2^s U - 1 where the two coincide.
      const double u = std::clamp((pre * r * scale - 1) / cap.m, 0.0, 1.0);
      worst = std::max(worst, distance_to_patch(evaluator, to_eigen(bp_grid_limit(p, r, j)), u, static_cast<double>(j) / p.n));
    }
  return worst;
}

}  // namespace subd2nurbs
