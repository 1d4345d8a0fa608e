// Patch builder: exact identities and continuity claims (MATH.md 5.3, 5.4, 6, 9).
//
// Oracles used here: the Bezier pieces themselves (blossoming must reproduce them exactly,
// which holds only if the pieces really join with the continuity the knot multiplicities
// claim), the limit masks (regular patches interpolate the limit at their corners), and the
// exact G1 identity D + E = 2c(1-t)^2 e' of Construction Q.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "common/shapes.h"
#include "core/eval/continuity.h"
#include "core/nurbs/nurbs_eval.h"
#include "core/patch/patch_builder.h"
#include "io/obj_reader.h"
#include "patch/patch_test_util.h"

namespace subd2nurbs::testing {
namespace {

TEST(Patches, RegularTorusIsOneC2BSplinePerQuad) {
  const MeshInput in = torus(8, 6);
  const PatchBuild b = build_from_input(in);
  EXPECT_EQ(b.info.coarse_level, 0);
  EXPECT_EQ(b.info.level, 0);  // every quad is one bicubic already: nothing is refined
  ASSERT_EQ(static_cast<int>(b.set.patches.size()), 48);
  EXPECT_EQ(b.info.regular_patches, 48);
  EXPECT_TRUE(b.set.closed);
  for (const NurbsPatch& p : b.set.patches) {
    EXPECT_EQ(p.num_poles_u, 4);  // one span: the 16 poles of the quad's bicubic
    EXPECT_EQ(p.num_poles_v, 4);
  }
  EXPECT_EQ(b.info.total_poles, 48 * 16);
  const ContinuityReport r = measure_continuity(b.set);
  const double tol = 1e-12 * b.set.model_size;
  EXPECT_LT(r.max_gap, tol);
  EXPECT_LT(r.max_c1_jump, 1e-11);
  EXPECT_LT(r.max_c2_jump, 1e-10);
  EXPECT_LT(max_piece_error(b), tol);
  EXPECT_LT(max_corner_limit_error(b), tol);
}

// PatchEvaluator against the rational Bernstein form written out (a bicubic Bezier patch on
// the domain [1, 3] x [-1, 2], weights not 1): position and first derivatives by the quotient
// rule, second derivatives by central differences of the first; lower orders give the same
// numbers as order 2.
TEST(Patches, PatchEvaluatorIsTheRationalBernsteinForm) {
  NurbsPatch p;
  p.knots_u = {{1.0, 3.0}, {4, 4}};
  p.knots_v = {{-1.0, 2.0}, {4, 4}};
  p.num_poles_u = p.num_poles_v = 4;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      p.poles.push_back({i + 0.3 * j * j, j - 0.2 * i * j, std::sin(i + 2.0 * j)});
      p.weights.push_back(1.0 + 0.1 * ((i * 7 + j * 3) % 5));
    }
  auto bern = [](double t, double b[4], double db[4]) {
    const double s = 1 - t;
    b[0] = s * s * s; b[1] = 3 * t * s * s; b[2] = 3 * t * t * s; b[3] = t * t * t;
    db[0] = -3 * s * s; db[1] = 3 * s * s - 6 * t * s; db[2] = 6 * t * s - 3 * t * t; db[3] = 3 * t * t;
  };
  const PatchEvaluator eval(p);
  for (double u : {1.0, 1.37, 2.5, 3.0})
    for (double v : {-1.0, 0.2, 1.9, 2.0}) {
      double bu[4], dbu[4], bv[4], dbv[4];
      bern((u - 1) / 2, bu, dbu);
      bern((v + 1) / 3, bv, dbv);
      double A[3] = {}, Au[3] = {}, Av[3] = {}, w = 0, wu = 0, wv = 0;
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
          const double wt = p.weights[i * 4 + j];
          w += bu[i] * bv[j] * wt;
          wu += dbu[i] / 2 * bv[j] * wt;
          wv += bu[i] * dbv[j] / 3 * wt;
          for (int c = 0; c < 3; ++c) {
            A[c] += bu[i] * bv[j] * wt * p.pole(i, j)[c];
            Au[c] += dbu[i] / 2 * bv[j] * wt * p.pole(i, j)[c];
            Av[c] += bu[i] * dbv[j] / 3 * wt * p.pole(i, j)[c];
          }
        }
      const SurfaceDerivs d = eval.derivs(u, v);
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(d.p[c], A[c] / w, 1e-14);
        EXPECT_NEAR(d.du[c], (Au[c] - wu * A[c] / w) / w, 1e-13);
        EXPECT_NEAR(d.dv[c], (Av[c] - wv * A[c] / w) / w, 1e-13);
      }
      const double h = 1e-5;
      const double ui = std::clamp(u, 1 + h, 3 - h), vi = std::clamp(v, -1 + h, 2 - h);
      const SurfaceDerivs c0 = eval.derivs(ui, vi), up = eval.derivs(ui + h, vi), um = eval.derivs(ui - h, vi),
                          vp = eval.derivs(ui, vi + h), vm = eval.derivs(ui, vi - h);
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(c0.duu[c], (up.du[c] - um.du[c]) / (2 * h), 1e-7);
        EXPECT_NEAR(c0.duv[c], (vp.du[c] - vm.du[c]) / (2 * h), 1e-7);
        EXPECT_NEAR(c0.dvv[c], (vp.dv[c] - vm.dv[c]) / (2 * h), 1e-7);
      }
      const SurfaceDerivs d1 = eval.derivs(u, v, 1);
      EXPECT_EQ(eval.point(u, v), d.p);
      EXPECT_EQ(d1.p, d.p);
      EXPECT_EQ(d1.du, d.du);
      EXPECT_EQ(d1.dv, d.dv);
      EXPECT_EQ(d1.duu, (Point3{0, 0, 0}));
      const SurfaceDerivs e = evaluate(p, u, v);
      EXPECT_EQ(e.duv, d.duv);
    }
  EXPECT_THROW(eval.derivs(2, 0, 3), std::invalid_argument);
  // The grid evaluation is the same rational sum, point by point, on grids beyond the 16
  // parameters it keeps on the stack.
  for (int n : {1, 4, 9, 17, 40}) {
    std::vector<double> us(n), vs(n + 3);
    for (int a = 0; a < n; ++a) us[a] = 1 + 2.0 * a / std::max(1, n - 1);
    for (int b = 0; b < n + 3; ++b) vs[b] = -1 + 3.0 * b / (n + 2);
    std::vector<Point3> grid(us.size() * vs.size());
    eval.grid(us.data(), n, vs.data(), n + 3, grid.data());
    for (int a = 0; a < n; ++a)
      for (int b = 0; b < n + 3; ++b)
        for (int c = 0; c < 3; ++c)
          EXPECT_NEAR(grid[a * (n + 3) + b][c], eval.point(us[a], vs[b])[c], 1e-14) << n << " " << a << " " << b;
  }
}

TEST(Patches, StarsAreExactlyG1AtTheExtraordinaryVertex) {
  for (int n : {3, 5, 6, 7, 8, 12}) {
    SCOPED_TRACE("valence " + std::to_string(n));
    const MeshInput in = star(n);
    const PatchBuild b = build_from_input(in);
    EXPECT_EQ(b.info.coarse_level, 1);  // the bottom n-gon is split first
    const ContinuityReport r = measure_continuity(b.set);
    EXPECT_LT(r.max_gap, 1e-12 * b.set.model_size);
    EXPECT_LT(r.max_normal_angle_deg, 1e-6);
    EXPECT_LT(r.max_coplanarity, 1e-10);
    EXPECT_LT(max_piece_error(b), 1e-12 * b.set.model_size);
    EXPECT_LT(max_g1_residual(b), 1e-12);
    EXPECT_GT(b.info.pccm_patches, 0);
  }
}

TEST(Patches, G1ResidualTestCanFail) {
  // Perturb one pole next to an extraordinary ray: the exact residual must notice.
  const MeshInput in = star(5);
  PatchBuild b = build_from_input(in);
  ASSERT_FALSE(b.info.rays.empty());
  const RayCurve& ray = b.info.rays.front();
  const CurveUse& use = b.set.curves[ray.curve].uses[0];
  NurbsPatch& p = b.set.patches[use.patch];
  p.pole(1, 1)[2] += 1e-3;
  p.pole(p.num_poles_u - 2, 1)[2] += 1e-3;
  p.pole(1, p.num_poles_v - 2)[2] += 1e-3;
  p.pole(p.num_poles_u - 2, p.num_poles_v - 2)[2] += 1e-3;
  EXPECT_GT(max_g1_residual(b), 1e-6);
}

}  // namespace
}  // namespace subd2nurbs::testing
