// Deviation of Construction Q from the Catmull-Clark limit (closest-point distance), and its
// rate of decrease per level against the rates MATH.md 5.3 derives per valence.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "core/eval/deviation.h"
#include "patch/patch_test_util.h"

namespace subd2nurbs::testing {
namespace {

// An open disc of n sectors, each an M x M grid of quads, around one extraordinary vertex of
// valence n; the points lie on the quadratic height field z = f(x, y) over a planar layout
// whose sector s spans the directions 2 pi s / n and 2 pi (s + 1) / n.
MeshInput sector_disc(int n, int M) {
  MeshInput m;
  auto f = [](double x, double y) { return 0.3 * x * x + 0.1 * x * y - 0.2 * y * y; };
  m.positions.push_back({0, 0, 0});
  // Sector s owns the points (i, j), i >= 1, j >= 0; (0, j) is sector s+1's (j, 0).
  auto index = [&](int s, int i, int j) {
    if (i == 0 && j == 0) return 0;
    if (i == 0) { s = (s + 1) % n; i = j; j = 0; }
    return 1 + s * (M * (M + 1)) + (i - 1) * (M + 1) + j;
  };
  const double scale = 1.0 / M;
  for (int s = 0; s < n; ++s)
    for (int i = 1; i <= M; ++i)
      for (int j = 0; j <= M; ++j) {
        const double a = 2 * M_PI * s / n, b = 2 * M_PI * (s + 1) / n;
        const double x = scale * (i * std::cos(a) + j * std::cos(b)), y = scale * (i * std::sin(a) + j * std::sin(b));
        m.positions.push_back({x, y, f(x, y)});
      }
  for (int s = 0; s < n; ++s)
    for (int i = 0; i < M; ++i)
      for (int j = 0; j < M; ++j) {
        m.face_sizes.push_back(4);
        for (int v : {index(s, i, j), index(s, i + 1, j), index(s, i + 1, j + 1), index(s, i, j + 1)})
          m.face_indices.push_back(v);
      }
  return m;
}

TEST(Deviation, RegularSurfaceHasNoDeviationToMeasure) {
  const PatchBuild b = build_from_input(sector_disc(4, 4));
  EXPECT_TRUE(b.info.fans.empty());
  EXPECT_EQ(measure_deviation(b).max, 0.0);
}

TEST(Deviation, SectorDiscIsG1AndItsDeviationIsSmall) {
  for (int n : {3, 5, 6, 8}) {
    SCOPED_TRACE("valence " + std::to_string(n));
    const PatchBuild b = build_from_input(sector_disc(n, 4));
    ASSERT_EQ(b.info.fans.size(), 1u);
    EXPECT_EQ(b.info.fans[0].mode, FanMode::Smooth);
    EXPECT_LT(max_g1_residual(b), 1e-12);
    const DeviationReport d = measure_deviation(b);
    EXPECT_GT(d.samples, 100);
    // MATH.md 5.3: 0.07 - 2.1 % of the level-k edge length at the EV on smooth data.
    const double h = 1.0 / 4 / 4;  // cage edge 1/M, two levels
    EXPECT_GT(d.max, 0.0);
    EXPECT_LT(d.max, 0.05 * h);
  }
}

TEST(Deviation, MeasureNoticesAMovedPole) {
  PatchBuild b = build_from_input(sector_disc(5, 4));
  const double before = measure_deviation(b).max;
  // Move an interior point of a zone net by 1e-2 along z: the surface moves by up to
  // (4/9)^2 * 1e-2 = 2e-3 there, ten times the deviation before.
  FanPiece& piece = b.fan_pieces[b.info.fans[0].piece];
  const PolyMesh& mk = piece.mesh.level.mesh;
  const int f = mk.corner_face(mk.vertex_corners(piece.vertex)[0]);
  piece.nets[static_cast<size_t>(f) * 16 + 5][2] += 1e-2;
  EXPECT_LT(before, 5e-4);
  EXPECT_GT(measure_deviation(b).max, 1.5e-3);
}

// The deviation falls per level by 1/max(lambda_n^2, mu_n) asymptotically (MATH.md 5.3).
class DeviationRate : public ::testing::TestWithParam<int> {};
TEST_P(DeviationRate, MatchesMathWithin15Percent) {
  const int n = GetParam();
  const MeshInput in = sector_disc(n, 3);
  double previous = -1, ratio = 0;
  for (int extra = 0; extra <= 3; ++extra) {
    const PatchBuild b = build_from_input(in, extra);
    const double d = measure_deviation(b).max;
    if (previous > 0) ratio = previous / d;
    previous = d;
  }
  const double expected = deviation_rate(n);
  RecordProperty("measured_rate", std::to_string(ratio));
  EXPECT_NEAR(ratio / expected, 1.0, 0.15) << "measured " << ratio << ", MATH.md " << expected;
}
INSTANTIATE_TEST_SUITE_P(Valences, DeviationRate, ::testing::Values(3, 5, 6, 8, 12));

TEST(Deviation, RateFormulaValues) {
  // MATH.md 5.3: about 6 (n = 3), 2.94 (5), 2.44 (6), 2.00 (8), 1.73 (12); exactly 4 for n = 4.
  EXPECT_NEAR(deviation_rate(3), 5.95, 0.05);
  EXPECT_NEAR(deviation_rate(4), 4.0, 1e-12);
  EXPECT_NEAR(deviation_rate(5), 2.94, 0.01);
  EXPECT_NEAR(deviation_rate(6), 2.44, 0.01);
  EXPECT_NEAR(deviation_rate(8), 2.00, 0.01);
  EXPECT_NEAR(deviation_rate(12), 1.73, 0.01);
}

}  // namespace
}  // namespace subd2nurbs::testing
