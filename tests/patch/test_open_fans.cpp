// Irregular vertices on a boundary or crease (MATH.md 5.6 made precise, docs/patches.md):
// open fans of k sectors between two sharp edges are exactly G1 across their interior rays,
// and their deviation from the limit shrinks with the level.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>
#include <tuple>

#include "core/eval/continuity.h"
#include "core/eval/deviation.h"
#include "patch/patch_test_util.h"

namespace subd2nurbs::testing {
namespace {

// k sectors of M x M quads around vertex 0, spanning `angle` in the plane, lifted onto a
// quadratic height field. Rays 0 and k are the boundary.
MeshInput open_fan(int k, int M, double angle) {
  MeshInput m;
  auto f = [](double x, double y) { return 0.25 * x * x - 0.15 * x * y + 0.1 * y * y; };
  std::map<std::tuple<int, int, int>, int> ids;  // (ray or -1-sector, i, j)
  auto dir = [&](int r) { return std::array<double, 2>{std::cos(angle * r / k), std::sin(angle * r / k)}; };
  auto id = [&](int s, int i, int j) {
    std::tuple<int, int, int> key;
    if (i == 0 && j == 0) key = {0, 0, 0};
    else if (i == 0) key = {s + 1, j, 0};
    else if (j == 0) key = {s, i, 0};
    else key = {-1 - s, i, j};
    auto it = ids.find(key);
    if (it != ids.end()) return it->second;
    const auto a = dir(s), b = dir(s + 1);
    const double x = (i * a[0] + j * b[0]) / M, y = (i * a[1] + j * b[1]) / M;
    m.positions.push_back({x, y, f(x, y)});
    return ids[key] = static_cast<int>(m.positions.size()) - 1;
  };
  for (int s = 0; s < k; ++s)
    for (int i = 0; i < M; ++i)
      for (int j = 0; j < M; ++j) {
        m.face_sizes.push_back(4);
        for (int v : {id(s, i, j), id(s, i + 1, j), id(s, i + 1, j + 1), id(s, i, j + 1)}) m.face_indices.push_back(v);
      }
  return m;
}

void check_open_fan(const MeshInput& in, FanMode mode) {
  double previous = -1;
  for (int extra = 0; extra <= 2; ++extra) {
    const PatchBuild b = build_from_input(in, extra);
    int found = 0;
    for (const IrregularFan& fan : b.info.fans) found += fan.vertex == 0 && fan.mode == mode;
    ASSERT_EQ(found, 1);
    EXPECT_LT(max_g1_residual(b), 1e-12);
    const ContinuityReport r = measure_continuity(b.set);
    EXPECT_LT(r.max_normal_angle_deg, 1e-6);
    EXPECT_LT(r.max_gap, 1e-14 * b.set.model_size);
    EXPECT_LT(max_piece_error(b), 1e-13 * b.set.model_size);
    const double d = measure_deviation(b).max;
    if (previous > 0) EXPECT_GT(previous / d, 1.3) << "deviation " << previous << " -> " << d;
    previous = d;
  }
}

TEST(OpenFans, BoundaryVertexWithKFacesIsExactlyG1) {
  for (int k : {3, 4, 5, 6}) {
    SCOPED_TRACE("k = " + std::to_string(k));
    check_open_fan(open_fan(k, 3, M_PI), FanMode::Crease);
  }
}

TEST(OpenFans, CornerVertexWithKFacesIsExactlyG1) {
  for (int k : {2, 3, 4}) {
    SCOPED_TRACE("k = " + std::to_string(k));
    MeshInput in = open_fan(k, 3, M_PI / 2);
    in.corners.push_back({0, kInfiniteSharpness});
    check_open_fan(in, FanMode::Corner);
  }
}

TEST(OpenFans, RegularBoundaryNeedsNoFan) {
  const PatchBuild b = build_from_input(open_fan(2, 3, M_PI));
  for (const IrregularFan& fan : b.info.fans) EXPECT_NE(fan.vertex, 0);
}

}  // namespace
}  // namespace subd2nurbs::testing
