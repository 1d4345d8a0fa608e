// Fairing (core/fit/fairing.h): the energy against an independent quadrature of our exact limit
// evaluator's derivatives, its convergence at extraordinary vertices, the seed-002 grid masks,
// and the fits (monotone in the weight, kept vertices fixed, noisy sphere made smooth).
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cstdio>
#include <cstring>

#include "core/fit/fairing.h"
#include "core/fit/interpolate.h"
#include "fit_test_util.h"

using namespace subd2nurbs;
using namespace subd2nurbs::testing;

namespace {

/// Thin-plate and membrane integrals of the limit surface, by 6 x 6 Gauss-Legendre quadrature
/// per ptex face of our exact evaluator's derivatives (exact for bicubic pieces).
std::pair<double, double> quadrature_energy(const SubdivLevel& level, const std::vector<Point3>& p) {
  const double x[6] = {-0.9324695142031521, -0.6612093864662645, -0.2386191860831969,
                       0.2386191860831969,  0.6612093864662645,  0.9324695142031521};
  const double w[6] = {0.1713244923791704, 0.3607615730481386, 0.4679139345726910,
                       0.4679139345726910, 0.3607615730481386, 0.1713244923791704};
  const LimitEvaluator ev(level, p);
  double tp = 0, mem = 0;
  for (int f = 0; f < ev.num_ptex_faces(); ++f)
    for (int a = 0; a < 6; ++a)
      for (int b = 0; b < 6; ++b) {
        const LimitSample s = ev.evaluate_ptex(f, (x[a] + 1) / 2, (x[b] + 1) / 2);
        const double wt = w[a] * w[b] / 4;
        for (int c = 0; c < 3; ++c) {
          tp += wt * (s.duu[c] * s.duu[c] + 2 * s.duv[c] * s.duv[c] + s.dvv[c] * s.dvv[c]);
          mem += wt * (s.du[c] * s.du[c] + s.dv[c] * s.dv[c]);
        }
      }
  return {tp, mem};
}

MeshInput wavy_torus() {
  LoadedCage cage = read_obj(limit_corpus_path("catmark_torus"));
  MeshInput in = cage.input;
  for (size_t i = 0; i < in.positions.size(); ++i) {
    in.positions[i][0] += 0.05 * std::sin(3.0 * i);
    in.positions[i][2] += 0.07 * std::cos(5.0 * i);
  }
  return in;
}

double mean_curvature_std(const SubdivLevel& level, const std::vector<Point3>& p) {
  const LimitEvaluator ev(level, p);
  double s = 0, s2 = 0;
  long n = 0;
  for (int f = 0; f < ev.num_ptex_faces(); ++f)
    for (double u : {0.2, 0.5, 0.8})
      for (double v : {0.2, 0.5, 0.8}) {
        const double h = ev.evaluate_ptex(f, u, v).mean;
        if (!std::isfinite(h)) continue;
        s += h;
        s2 += h * h;
        ++n;
      }
  const double mean = s / n;
  return std::sqrt(std::max(0.0, s2 / n - mean * mean));
}

}  // namespace

// On a cage that is regular everywhere every face is one bicubic patch: the Gram-matrix energy
// must equal the quadrature of the exact evaluator's derivatives, and refining first (levels
// 1, 2) must not change it (B-spline refinement is exact; the 4^k scale is right).
TEST(FairingEnergy, ExactOnRegularCagesAgainstQuadrature) {
  const MeshInput in = wavy_torus();
  const SubdivLevel level = SubdivLevel::from_input(in);
  const std::vector<Point3> p = positions_of(in);
  const auto [tp, mem] = quadrature_energy(level, p);
  for (int k : {0, 1, 2}) {
    const double e_tp = energy(energy_matrix(level, {1.0, 0.0, k}), p);
    const double e_mem = energy(energy_matrix(level, {0.0, 1.0, k}), p);
    EXPECT_NEAR(e_tp, tp, 1e-11 * tp) << "levels " << k;
    EXPECT_NEAR(e_mem, mem, 1e-11 * mem) << "levels " << k;
    std::printf("torus, levels %d: thin plate %.15g (quadrature %.15g), membrane %.15g (%.15g)\n", k, e_tp, tp,
                e_mem, mem);
  }
}

// Near extraordinary vertices the energy leaves out the level-k faces within 2^-k of them; the
// rest is exact, so the energy increases with k and converges (differences shrink).
TEST(FairingEnergy, ConvergesAtExtraordinaryVertices) {
  const MeshInput in = cube_sphere(4, 1.0, 0.05, 7);
  const SubdivLevel level = SubdivLevel::from_input(in);
  const std::vector<Point3> p = positions_of(in);
  std::vector<double> e;
  for (int k = 0; k <= 4; ++k) e.push_back(energy(energy_matrix(level, {1.0, 0.0, k}), p));
  std::printf("cube sphere n = 4: thin-plate energy at levels 0..4: %.10g %.10g %.10g %.10g %.10g\n", e[0], e[1],
              e[2], e[3], e[4]);
  for (int k = 1; k <= 4; ++k) EXPECT_GT(e[k], e[k - 1]);
  // Level j adds the ring of level-j faces around each valence-3 vertex; in their own
  // parameters their second differences scale like lambda_3^j, so in ptex units the ring's
  // energy scales like 4^j lambda_3^2j: increments shrink by 4 lambda_3^2 = 0.6727 per level
  // (lambda_3 = 0.410097, the subdominant eigenvalue at valence 3).
  const double lambda3 = (5 + std::cos(2 * M_PI / 3) + std::cos(M_PI / 3) * std::sqrt(2 * (9 + std::cos(2 * M_PI / 3)))) / 16;
  const double rate = 4 * lambda3 * lambda3;
  const double r3 = (e[3] - e[2]) / (e[2] - e[1]), r4 = (e[4] - e[3]) / (e[3] - e[2]);
  std::printf("increment ratios %.4f %.4f, predicted %.4f\n", r3, r4, rate);
  EXPECT_NEAR(r3, rate, 0.03);
  EXPECT_NEAR(r4, rate, 0.03);
  RecordProperty("energy_levels_2_3_4", std::to_string(e[2]) + " " + std::to_string(e[3]) + " " + std::to_string(e[4]));
}

// Weimer-Warren's thin-plate masks (seed 002, the discrete energy D_uu^T D_uu + 2 D_uv^T D_uv +
// D_vv^T D_vv on a grid): interior, one row in, boundary, diagonal, next to a corner, corner.
TEST(FairingEnergy, SeedTwoGridMasks) {
  const int n = 9;
  const Eigen::MatrixXd K(grid_thin_plate_matrix(n, n));
  auto mask = [&](int i, int j, int di, int dj) {  // entry of row (i, j) at (i + di, j + dj)
    const int a = i + di, b = j + dj;
    if (a < 0 || b < 0 || a >= n || b >= n) return 0.0;
    return K(i + n * j, a + n * b);
  };
  // Interior: [0 0 1 0 0 / 0 2 -8 2 0 / 1 -8 20 -8 1 / 0 2 -8 2 0 / 0 0 1 0 0].
  const double interior[5][5] = {{0, 0, 1, 0, 0}, {0, 2, -8, 2, 0}, {1, -8, 20, -8, 1}, {0, 2, -8, 2, 0}, {0, 0, 1, 0, 0}};
  for (int a = 0; a < 5; ++a)
    for (int b = 0; b < 5; ++b) EXPECT_EQ(mask(4, 4, a - 2, b - 2), interior[a][b]);
  EXPECT_EQ(mask(1, 4, 0, 0), 19);   // one row inside the boundary
  EXPECT_EQ(mask(1, 4, -1, 0), -6);  // its neighbour toward the boundary
  // On the boundary (i = 0): [1 -6 11 -6 1 / 0 2 -6 2 0 / 0 0 1 0 0], first row along it.
  const double boundary[3][5] = {{1, -6, 11, -6, 1}, {0, 2, -6, 2, 0}, {0, 0, 1, 0, 0}};
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 5; ++b) EXPECT_EQ(mask(0, 4, a, b - 2), boundary[a][b]);
  EXPECT_EQ(mask(1, 1, 0, 0), 18);  // diagonal one in
  EXPECT_EQ(mask(0, 1, 0, 0), 10);  // boundary next to a corner
  const double corner[3][3] = {{4, -4, 1}, {-4, 2, 0}, {1, 0, 0}};
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) EXPECT_EQ(mask(0, 0, a, b), corner[a][b]);
  // Null space: constants and linear functions, dimension 3.
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(K);
  int zero = 0;
  for (int i = 0; i < n * n; ++i) zero += std::abs(es.eigenvalues()[i]) < 1e-9;
  EXPECT_EQ(zero, 3);
}

// fair(): the energy of the result decreases monotonically as the weight grows, the data term
// increases, and kept vertices are bit-identical.
TEST(Fairing, MonotoneInWeightAndKeepsVertices) {
  const LoadedCage cage = read_obj(limit_corpus_path("catmark_square_hedit0"));
  MeshInput in = cage.input;
  for (size_t i = 0; i < in.positions.size(); ++i) in.positions[i][2] += 0.1 * std::sin(7.0 * i);
  const SubdivLevel level = SubdivLevel::from_input(in);
  const std::vector<Point3> p = positions_of(in);
  std::vector<Point3> lim;
  limit_rows(level).rows.apply(p, lim);
  FairOptions opt;
  opt.keep = kept_vertices(level, {true, false, false});
  int kept = 0;
  for (char k : opt.keep) kept += k;
  ASSERT_GT(kept, 0);
  double prev_e = 1e300, prev_d = -1;
  for (double w : {1e-4, 1e-3, 1e-2, 1e-1, 1.0, 10.0, 100.0}) {
    opt.weight = w;
    const FairResult r = fair(level, p, lim, opt);
    std::printf("W = %g: energy %.10g -> %.10g, data %.3e\n", w, r.energy_before, r.energy_after, r.data_after);
    EXPECT_LT(r.energy_after, prev_e) << w;
    EXPECT_GT(r.data_after, prev_d) << w;
    EXPECT_LT(r.energy_after, r.energy_before) << w;
    prev_e = r.energy_after;
    prev_d = r.data_after;
    int moved = 0;
    for (size_t v = 0; v < p.size(); ++v) {
      if (opt.keep[v]) {
        EXPECT_EQ(std::memcmp(&r.positions[v], &p[v], sizeof(Point3)), 0) << "vertex " << v;
      } else {
        moved += dist(r.positions[v], p[v]) > 0;
      }
    }
    EXPECT_GT(moved, 0);
  }
}

TEST(Fairing, RejectsNonPositiveWeight) {
  const LoadedCage cage = read_obj(limit_corpus_path("catmark_torus"));
  const SubdivLevel level = SubdivLevel::from_input(cage.input);
  const std::vector<Point3> p = positions_of(cage.input);
  for (double w : {0.0, -1.0, std::nan("")}) {
    FairOptions opt;
    opt.weight = w;
    EXPECT_THROW(fair(level, p, p, opt), std::invalid_argument);
  }
}

/// RMS of |x| - 1 over 9 limit points per face (distance from the unit sphere).
double radial_rms(const SubdivLevel& level, const std::vector<Point3>& p) {
  const LimitEvaluator ev(level, p);
  double s2 = 0;
  long n = 0;
  for (int f = 0; f < ev.num_ptex_faces(); ++f)
    for (double u : {0.2, 0.5, 0.8})
      for (double v : {0.2, 0.5, 0.8}) {
        const Point3 x = ev.evaluate_ptex(f, u, v).p;
        const double r = std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]) - 1;
        s2 += r * r;
        ++n;
      }
  return std::sqrt(s2 / n);
}

// A noisy sphere-like quad mesh: the plain interpolant reproduces the noise; the fair fit
// (least squares with the thin-plate energy as regulariser) is at least 5x smoother, measured
// as the standard deviation of the exact evaluator's mean curvature at 9 points per face.
TEST(Fairing, NoisySphereFairFitIsSmoother) {
  const MeshInput in = cube_sphere(8, 1.0, 0.03, 11);
  const SubdivLevel level = SubdivLevel::from_input(in);
  const std::vector<Point3> c = positions_of(in);
  const InterpolationResult plain = interpolate(level, c);
  FairOptions opt;
  opt.weight = 0.3;
  const FairResult faired = fair(level, plain.positions, c, opt);
  const double s_plain = mean_curvature_std(level, plain.positions);
  const double s_fair = mean_curvature_std(level, faired.positions);
  const double s_cage = mean_curvature_std(level, c);
  std::vector<Point3> lim;
  limit_rows(level).rows.apply(faired.positions, lim);
  const FieldStats miss = field_stats(lim, c);
  const double rms_plain = radial_rms(level, plain.positions), rms_fair = radial_rms(level, faired.positions);
  std::printf("distance to the unit sphere (rms over the samples): interpolant %.4g, fair fit %.4g\n", rms_plain,
              rms_fair);
  EXPECT_LT(rms_fair, rms_plain);
  std::printf("noisy sphere (n = 8, noise 3%%): std of mean curvature: interpolant %.4g, fair fit (W = %g) %.4g, "
              "approximating (cage as is) %.4g; ratio %.2f; fair fit misses the points by max %.3g, mean %.3g\n",
              s_plain, opt.weight, s_fair, s_cage, s_plain / s_fair, miss.max, miss.mean);
  RecordProperty("curvature_std_interpolant", std::to_string(s_plain));
  RecordProperty("curvature_std_fair", std::to_string(s_fair));
  EXPECT_GE(s_plain / s_fair, 5.0);
  EXPECT_LT(miss.max, 0.06);  // still close to the points (noise amplitude 0.03)
}
