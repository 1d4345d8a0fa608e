// smallest_curvature_radii (core/eval/curvature_radius.h) against an exact answer (a bicubic
// paraboloid: curvature 2a at its apex, less elsewhere) and against finite differences of the
// patch positions on a real cage (catmark_torus, packed and per quad), plus orientation.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "core/eval/curvature_radius.h"
#include "core/nurbs/nurbs_eval.h"
#include "core/patch/packing.h"
#include "core/patch/patch_builder.h"
#include "io/obj_reader.h"

namespace subd2nurbs {
namespace {

/// z = a (x^2 + y^2) over x, y in [-1, 1] as one bicubic Bezier patch on [0, 1]^2 (x = 2u - 1):
/// the cubic Bernstein coefficients of x are (-1, -1/3, 1/3, 1) and of x^2 (1, -1/3, -1/3, 1).
/// flip: u and v swapped, so the normal Xu x Xv points down instead of up.
PatchSet paraboloid(double a, bool flip) {
  const double x[4] = {-1, -1.0 / 3, 1.0 / 3, 1}, x2[4] = {1, -1.0 / 3, -1.0 / 3, 1};
  NurbsPatch p;
  p.knots_u.knots = p.knots_v.knots = {0, 1};
  p.knots_u.mults = p.knots_v.mults = {4, 4};
  p.num_poles_u = p.num_poles_v = 4;
  p.poles.resize(16);
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      p.pole(i, j) = flip ? Point3{x[j], x[i], a * (x2[i] + x2[j])} : Point3{x[i], x[j], a * (x2[i] + x2[j])};
  PatchSet ps;
  ps.patches.push_back(p);
  ps.closed = false;
  return ps;
}

TEST(CurvatureRadius, ParaboloidApexIsExact) {
  const double a = 0.7;  // radius 1 / (2a) at the apex (0.5, 0.5), larger everywhere else
  const CurvatureRadii up = smallest_curvature_radii(paraboloid(a, false));
  EXPECT_EQ(up.samples, 81);
  EXPECT_FALSE(up.outward);
  // It curves towards its normal (+z): an offset along the normal folds at 1 / (2a).
  EXPECT_NEAR(up.outward_offset.radius, 1 / (2 * a), 1e-12);
  EXPECT_EQ(up.outward_offset.patch, 0);
  EXPECT_DOUBLE_EQ(up.outward_offset.u, 0.5);
  EXPECT_DOUBLE_EQ(up.outward_offset.v, 0.5);
  EXPECT_NEAR(up.outward_offset.point[2], 0, 1e-15);
  EXPECT_TRUE(std::isinf(up.inward.radius));  // convex nowhere
  // The normal turned around: the same radius, on the other side.
  const CurvatureRadii down = smallest_curvature_radii(paraboloid(a, true));
  EXPECT_NEAR(down.inward.radius, 1 / (2 * a), 1e-12);
  EXPECT_TRUE(std::isinf(down.outward_offset.radius));
}

TEST(CurvatureRadius, FlatPatchHasNoLimit) {
  // The plane z = 0 turned by arbitrary angles: its poles carry rounding, so its second
  // derivatives are ~1e-16 rather than 0; no radius either way, not 1e15.
  PatchSet ps = paraboloid(0, false);
  const double a = 0.7, b = 1.3;
  for (Point3& q : ps.patches[0].poles) {
    const Point3 r1{q[0], std::cos(a) * q[1] - std::sin(a) * q[2], std::sin(a) * q[1] + std::cos(a) * q[2]};
    q = {std::cos(b) * r1[0] + std::sin(b) * r1[2], r1[1], -std::sin(b) * r1[0] + std::cos(b) * r1[2]};
  }
  const CurvatureRadii r = smallest_curvature_radii(ps);
  EXPECT_EQ(r.samples, 81);
  EXPECT_EQ(r.inward.patch, -1);
  EXPECT_EQ(r.outward_offset.patch, -1);
  EXPECT_TRUE(std::isinf(r.inward.radius) && std::isinf(r.outward_offset.radius));
}

/// Principal curvatures by central differences of positions only (h in parameter units):
/// the fundamental forms from finite-difference derivatives.
void finite_difference_k(const NurbsPatch& patch, double u, double v, double sign, double& k_min, double& k_max) {
  const PatchEvaluator e(patch);
  const double h = 1e-3;
  auto P = [&](double du, double dv) { return e.point(u + du, v + dv); };
  auto comb = [](const Point3& a, const Point3& b, double s) {
    return Point3{(a[0] - b[0]) * s, (a[1] - b[1]) * s, (a[2] - b[2]) * s};
  };
  auto add = [](const Point3& a, const Point3& b) { return Point3{a[0] + b[0], a[1] + b[1], a[2] + b[2]}; };
  auto dot = [](const Point3& a, const Point3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
  const Point3 c = P(0, 0);
  const Point3 xu = comb(P(h, 0), P(-h, 0), 1 / (2 * h)), xv = comb(P(0, h), P(0, -h), 1 / (2 * h));
  const Point3 xuu = comb(add(P(h, 0), P(-h, 0)), add(c, c), 1 / (h * h));
  const Point3 xvv = comb(add(P(0, h), P(0, -h)), add(c, c), 1 / (h * h));
  const Point3 xuv = comb(add(P(h, h), P(-h, -h)), add(P(h, -h), P(-h, h)), 1 / (4 * h * h));
  Point3 n{xu[1] * xv[2] - xu[2] * xv[1], xu[2] * xv[0] - xu[0] * xv[2], xu[0] * xv[1] - xu[1] * xv[0]};
  const double len = std::sqrt(dot(n, n));
  for (double& x : n) x *= sign / len;
  const double E = dot(xu, xu), F = dot(xu, xv), G = dot(xv, xv);
  const double L = dot(xuu, n), M = dot(xuv, n), N = dot(xvv, n), det = E * G - F * F;
  const double H = (E * N - 2 * F * M + G * L) / (2 * det), K = (L * N - M * M) / det;
  const double r = std::sqrt(std::max(0.0, H * H - K));
  k_min = H - r;
  k_max = H + r;
}

TEST(CurvatureRadius, TorusCageAgreesWithFiniteDifferences) {
  const LoadedCage cage = read_obj(std::string(SUBD2NURBS_CORPUS_DIR) + "/catmark_torus.obj");
  const PatchBuild b = build_patches(SubdivLevel::from_input(cage.input), cage.input.positions);
  double core = 0;
  for (const Point3& q : cage.input.positions) core += std::hypot(q[0], q[2]) / cage.input.positions.size();
  for (const bool packed : {false, true}) {
    SCOPED_TRACE(packed ? "packed" : "per quad");
    const PatchSet ps = packed ? pack_patches(b).set : b.set;
    const CurvatureRadii r = smallest_curvature_radii(ps, 8);
    ASSERT_TRUE(r.outward);
    ASSERT_TRUE(std::isfinite(r.inward.radius));
    ASSERT_TRUE(std::isfinite(r.outward_offset.radius));
    // The tube is convex all round its outside and saddle-shaped inside: both kinds occur,
    // and the tube's radius (the cage's is 0.35) bounds the convex one from above.
    EXPECT_LT(r.inward.radius, 0.5);
    EXPECT_GT(r.inward.radius, 0.1);
    // Its sign convention (outward normal) found without being told the patches' orientation,
    // and the values at the reported places by finite differences (away from knot lines, a
    // sample one tiny step inside the span gives the same curvature to O(h)).
    for (const CurvatureRadiusAt* at : {&r.inward, &r.outward_offset}) {
      const NurbsPatch& patch = ps.patches[at->patch];
      const double u = std::min(std::max(at->u, patch.knots_u.knots.front() + 2e-3), patch.knots_u.knots.back() - 2e-3);
      const double v = std::min(std::max(at->v, patch.knots_v.knots.front() + 2e-3), patch.knots_v.knots.back() - 2e-3);
      // The outward side by geometry alone: away from the tube's core circle (the torus's
      // axis is y, its core radius the cage vertices' mean distance from the axis).
      const Point3 x = PatchEvaluator(patch).point(u, v);
      const double rho = std::hypot(x[0], x[2]);
      const Point3 away{x[0] - core * x[0] / rho, x[1], x[2] - core * x[2] / rho};
      const SurfaceDerivs d = evaluate(patch, u, v);
      const Point3 n = unit_normal(d);
      const double sign = n[0] * away[0] + n[1] * away[1] + n[2] * away[2] > 0 ? 1 : -1;
      double k_min, k_max;
      finite_difference_k(patch, u, v, sign, k_min, k_max);
      const double want = 1 / at->radius;
      const double got = at == &r.inward ? -k_min : k_max;
      EXPECT_NEAR(got, want, 0.02 * want);
    }
  }
}

}  // namespace
}  // namespace subd2nurbs
