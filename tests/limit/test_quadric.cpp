// Implicit-quadric normal and curvature (seed 001, MATH.md 8.3): analytic surfaces, and the
// fit to limit points converging to the exact limit curvature as the cage is refined.
#include <gtest/gtest.h>

#include <cmath>

#include <Eigen/Dense>

#include "core/eval/quadric_fit.h"
#include "common/shapes.h"
#include "limit_test_util.h"

using namespace subd2nurbs;
using namespace subd2nurbs::testing;

namespace {

/// Points around p0 on a surface given as z = h(x, y) - offset, on two rings of 6 and 7 angles.
template <class F>
std::vector<Point3> ring_points(F h, double r1, double r2) {
  std::vector<Point3> out;
  const double pi = std::acos(-1.0);
  for (int i = 0; i < 6; ++i) {
    const double a = 2 * pi * i / 6 + 0.1;
    out.push_back({r1 * std::cos(a), r1 * std::sin(a), h(r1 * std::cos(a), r1 * std::sin(a))});
  }
  for (int i = 0; i < 7; ++i) {
    const double a = 2 * pi * i / 7 + 0.3;
    out.push_back({r2 * std::cos(a), r2 * std::sin(a), h(r2 * std::cos(a), r2 * std::sin(a))});
  }
  return out;
}

}  // namespace

TEST(QuadricFit, MathChecksSphereSaddleCylinder) {
  // Sphere R = 2 through the origin, centre (0, 0, -2), outward normal +z (MATH.md 8.3).
  const double R = 2;
  auto sphere = [R](double x, double y) { return std::sqrt(R * R - x * x - y * y) - R; };
  QuadricFit f = fit_quadric({0, 0, 0}, ring_points(sphere, 0.3, 0.7), {0, 0, 1});
  ASSERT_TRUE(f.ok);
  EXPECT_NEAR(f.K, 0.25, 1e-9);
  EXPECT_NEAR(f.H, -0.5, 1e-9);
  EXPECT_NEAR(f.normal[2], 1.0, 1e-12);
  // The same with the tentative normal reversed: the curvature sign follows the normal.
  f = fit_quadric({0, 0, 0}, ring_points(sphere, 0.3, 0.7), {0.1, 0, -1});
  EXPECT_NEAR(f.H, 0.5, 1e-9);
  EXPECT_NEAR(f.K, 0.25, 1e-9);
  // Saddle (x^2 - y^2) / 2: K = -1, H = 0.
  f = fit_quadric({0, 0, 0}, ring_points([](double x, double y) { return (x * x - y * y) / 2; }, 0.2, 0.5),
                  {0, 0, 1});
  ASSERT_TRUE(f.ok);
  EXPECT_NEAR(f.K, -1.0, 1e-9);
  EXPECT_NEAR(f.H, 0.0, 1e-9);
  // Cylinder of radius 3 along y: K = 0, H = -1/(2 R).
  f = fit_quadric({0, 0, 0}, ring_points([](double x, double) { return std::sqrt(9 - x * x) - 3; }, 0.4, 0.9),
                  {0, 0, 1});
  ASSERT_TRUE(f.ok);
  EXPECT_NEAR(f.K, 0.0, 1e-9);
  EXPECT_NEAR(f.H, -1.0 / 6, 1e-9);
  // Too few points, or points on two lines: no fit.
  EXPECT_FALSE(fit_quadric({0, 0, 0}, {{1, 0, 0}, {0, 1, 0}}, {0, 0, 1}).ok);
  std::vector<Point3> lines;
  for (int i = 1; i <= 6; ++i) {
    lines.push_back({0.1 * i, 0, 0});
    lines.push_back({0, 0.1 * i, 0});
  }
  EXPECT_FALSE(fit_quadric({0, 0, 0}, lines, {0, 0, 1}).ok);
}

// Points exactly on a paraboloid z = (x^2 + xy + 3 y^2) / 4 (dyadic coordinates: the data has
// no rounding): the least-squares residual is 0 and the fit is the paraboloid, so its curvature
// at the origin is known in closed form (H = (q_xx + q_yy) / 2 = 1, K = q_xx q_yy - q_xy^2 =
// 11/16), however fine the ring. Fine rings are badly conditioned (the quadric terms shrink with
// the spacing); most are still solved directly (normal equations, quadric_fit.cpp), the finest
// by the QR, and all stay exact to 1e-13 relative.
TEST(QuadricFit, DirectSolveIsExactOnQuadricPointsDownToFineRings) {
  const double H = 1, K = 11.0 / 16;
  int direct = 0, qr = 0;
  for (int e = 2; e <= 14; ++e) {  // 2^-15 is refused: s_min / s_max <= 1e-9
    const double h = std::ldexp(1.0, -e);
    std::vector<Point3> nb;  // a sheared 5 x 5 grid of spacing h, as a vertex's 2-ring
    for (int i = -2; i <= 2; ++i)
      for (int j = -2; j <= 2; ++j)
        if (i != 0 || j != 0) {
          const double x = i * h + j * h / 8, y = j * h;
          nb.push_back({x, y, (x * x + x * y + 3 * y * y) / 4});
        }
    const QuadricFit f = fit_quadric({0, 0, 0}, nb, {0, 0, 1});
    ASSERT_TRUE(f.ok) << "h = 2^-" << e;
    EXPECT_NEAR(f.H, H, 1e-13) << "h = 2^-" << e;
    EXPECT_NEAR(f.K, K, 1e-13) << "h = 2^-" << e;
    (f.direct ? direct : qr)++;
  }
  EXPECT_GE(direct, 8);  // both paths are measured
  EXPECT_GE(qr, 2);
}

TEST(QuadricFit, RefusedExactlyWhereTheSystemIsRankDeficient) {
  // A saddle's two rings flattened towards the plane z = 0 by a factor e: the fit's system
  // loses rank as e -> 0 (the columns z^2, yz, zx vanish). The oracle is the definition: the
  // singular values of the least-squares matrix (built here as docs/math.md 13 writes it),
  // smallest / largest > 1e-9, against fit_quadric's decision (which skips the SVD where the
  // pivoted QR's diagonal already bounds the ratio).
  int refused = 0, fitted = 0;
  for (int k = 0; k <= 32; ++k) {
    const double e = std::pow(10.0, -k / 4.0);
    const std::vector<Point3> nb =
        ring_points([e](double x, double y) { return e * (x * x - 2 * y * y + 0.3 * x * y) / 2; }, 0.2, 0.5);
    double rho = 0;
    for (const Point3& q : nb) rho += q[0] * q[0] + q[1] * q[1] + q[2] * q[2];
    rho = std::sqrt(rho / nb.size());
    Eigen::MatrixXd A(nb.size(), 8);  // z's gradient coefficient fixed: the tentative normal is +z
    for (size_t r = 0; r < nb.size(); ++r) {
      const double x = nb[r][0] / rho, y = nb[r][1] / rho, z = nb[r][2] / rho;
      A.row(static_cast<Eigen::Index>(r)) << x * x, y * y, z * z, x * y, y * z, z * x, x, y;
    }
    const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(A).singularValues();
    const double ratio = sv(7) / sv(0);
    if (ratio > 0.5e-9 && ratio < 2e-9) continue;  // too close to the threshold to call
    const bool full_rank = ratio > 1e-9;
    EXPECT_EQ(fit_quadric({0, 0, 0}, nb, {0, 0, 1}).ok, full_rank) << "e = " << e << ", ratio " << ratio;
    (full_rank ? fitted : refused)++;
  }
  EXPECT_GT(fitted, 5);  // the sweep crosses the threshold
  EXPECT_GT(refused, 5);
}

TEST(QuadricFit, SecondOrderOnAnAnalyticTorus) {
  // Torus R = 2, r = 0.5 sampled on a 5 x 5 parameter grid of spacing d around a point:
  // the error in H against H = -(R + 2 r cos p) / (2 r (R + r cos p)) falls 4x per halving.
  const double R = 2, r = 0.5, t0 = 0.3, p0 = 0.7;
  auto X = [&](double t, double p) {
    return Point3{(R + r * std::cos(p)) * std::cos(t), (R + r * std::cos(p)) * std::sin(t), r * std::sin(p)};
  };
  const Point3 n = {std::cos(p0) * std::cos(t0), std::cos(p0) * std::sin(t0), std::sin(p0)};
  const double exact = -(R + 2 * r * std::cos(p0)) / (2 * r * (R + r * std::cos(p0)));
  double previous = -1;
  for (double d : {0.2, 0.1, 0.05, 0.025}) {
    std::vector<Point3> nb;
    for (int i = -2; i <= 2; ++i)
      for (int j = -2; j <= 2; ++j)
        if (i || j) nb.push_back(X(t0 + i * d, p0 + j * d));
    const QuadricFit f = fit_quadric(X(t0, p0), nb, n);
    ASSERT_TRUE(f.ok);
    const double err = std::abs(f.H - exact);
    if (previous > 0) {
      EXPECT_NEAR(err / previous, 0.25, 0.03);
    }
    previous = err;
  }
  EXPECT_LT(previous, 2e-3);
}

TEST(QuadricFit, FitToLimitPointsConvergesToTheExactLimitCurvature) {
  // The same limit surface described by finer and finer cages (uniform refinement of the
  // torus): the fit to the limit points of each vertex's 2-ring approaches the exact H.
  // A 32 x 16 torus cage (major radius 3, minor 1): its limit is close to a torus, so the
  // curvature varies slowly and a quadric describes each 2-ring well.
  const MeshInput in = subd2nurbs::testing::torus(32, 16);
  const SubdivLevel base = SubdivLevel::from_input(in);
  const Refinement r = refine_uniform(base, 2);
  const auto pos = r.positions(positions_of(in));
  double previous = -1;
  for (int level = 0; level <= 2; ++level) {
    const LimitEvaluator ev(r.levels[level], pos[level]);
    const VertexCurvatureComparison c = compare_vertex_curvature(ev);
    ASSERT_GT(c.vertices, 0);
    std::printf("level %d: %d vertices, max |H| %.3g, H error: cage fit max %.3g, limit fit max %.3g mean %.3g\n",
                level, c.vertices, c.max_abs_H, c.max_abs_H_error_cage, c.max_abs_H_error_limit,
                c.mean_abs_H_error_limit);
    // Second order in the 2-ring's size (QuadricFit.SecondOrderOnAnAnalyticTorus): the mean
    // error falls by more than 2 per level already before the asymptotic 4.
    if (previous > 0) {
      EXPECT_LT(c.mean_abs_H_error_limit, 0.5 * previous);
    }
    previous = c.mean_abs_H_error_limit;
  }
  EXPECT_LT(previous, 0.05 * 0.643);
}
