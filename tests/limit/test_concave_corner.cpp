// Concave corners (core/mesh/corner_sectors.h): the Catmull-Clark corner rule cannot cover a
// sector wider than 180 degrees between two sharp edges. An L-shaped prism cage, its outline
// edges infinitely sharp: at the two inner corners the front and back faces' sector spans 270
// degrees, and the exact limit near the corner in those faces is folded into the notch: its
// normal points into the prism (the oracle: the front plane's outward normal, (0, -1, 0)). Validation names both corners;
// tagging the sector's inside edges as creases, as its message says, unfolds it.
#include <gtest/gtest.h>

#include <string>

#include "core/mesh/validate.h"
#include "limit_test_util.h"

using namespace subd2nurbs;
using namespace subd2nurbs::testing;

namespace {

// The profile (x, z), counter-clockwise seen from -y: front faces (y = 0) face -y. The L's
// inner corner is (1, 1); the vertices on its outline at (1.6, 0) and (0, 1.5) make its three
// faces uneven (with squares the fold cancels out by symmetry: the limit there is degenerate, not
// folded).
constexpr double kProfile[8][2] = {{0, 0}, {1.6, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}, {0, 1.5}};

// Vertices: front profile i -> i, back -> 8 + i. Front quads A, B, C (the L), back the same
// reversed, one wall quad per profile segment; outline edges and the edges along y at the real
// corners infinitely sharp.
MeshInput l_prism() {
  MeshInput m;
  for (double y : {0.0, 1.0})
    for (const auto& p : kProfile) m.positions.push_back({p[0], y, p[1]});
  auto quad = [&](int a, int b, int c, int d) {
    m.face_sizes.push_back(4);
    m.face_indices.insert(m.face_indices.end(), {a, b, c, d});
  };
  const int front[3][4] = {{0, 1, 4, 7}, {1, 2, 3, 4}, {7, 4, 5, 6}};
  for (const auto& f : front) quad(f[0], f[1], f[2], f[3]);
  for (const auto& f : front) quad(8 + f[3], 8 + f[2], 8 + f[1], 8 + f[0]);
  for (int i = 0; i < 8; ++i) {
    const int j = (i + 1) % 8;
    quad(i, 8 + i, 8 + j, j);
    m.creases.push_back({i, j, kInfiniteSharpness});
    m.creases.push_back({8 + i, 8 + j, kInfiniteSharpness});
  }
  for (int i : {0, 2, 3, 4, 5, 6}) m.creases.push_back({i, 8 + i, kInfiniteSharpness});
  return m;
}

// Over the front and back L's three faces each: the limit normal at parameter distance `eps`
// from the inner corner (vertex 4 or 12) against the plane's outward normal; the smallest dot.
double worst_normal_at_inner_corners(const MeshInput& m, double eps) {
  const LimitEvaluator ev(SubdivLevel::from_input(m), positions_of(m));
  double worst = 1;
  for (int f = 0; f < 6; ++f) {
    const int* q = &m.face_indices[static_cast<std::size_t>(4 * f)];
    for (int k = 0; k < 4; ++k) {
      if (q[k] != 4 && q[k] != 12) continue;
      const double u = (k == 1 || k == 2) ? 1 - eps : eps, v = (k >= 2) ? 1 - eps : eps;
      const LimitSample s = ev.evaluate_ptex(ev.first_ptex(f), u, v);
      const double outward_y = f < 3 ? -1 : 1;
      worst = std::min(worst, s.normal[1] * outward_y);
    }
  }
  return worst;
}

}  // namespace

TEST(ConcaveCorner, CornerRuleFoldsAWideSectorAndCreasesInsideItUnfoldIt) {
  const MeshInput folded = l_prism();
  Diagnostics diagnostics;
  validate_and_build(folded, &diagnostics);
  std::vector<long> named;
  for (const Diagnostic& d : diagnostics)
    if (d.code == "concave-corner") {
      named.push_back(d.index);
      EXPECT_NE(d.message.find("3 faces between two sharp edges span 270 degrees"), std::string::npos) << d.message;
    }
  EXPECT_EQ(named, (std::vector<long>{4, 12}));
  // Folded: near the corner (1e-4 of the faces' parameters) the limit faces into the prism.
  for (const double eps : {1e-6, 1e-4}) EXPECT_LT(worst_normal_at_inner_corners(folded, eps), -0.9) << eps;

  MeshInput split = folded;
  for (int corner : {4, 12})
    for (int inside : {1, 7}) split.creases.push_back({corner, corner - 4 + inside, kInfiniteSharpness});
  Diagnostics after;
  validate_and_build(split, &after);
  for (const Diagnostic& d : after) EXPECT_NE(d.code, "concave-corner") << d.message;
  for (const double eps : {1e-6, 1e-4, 1e-2, 0.1}) EXPECT_GT(worst_normal_at_inner_corners(split, eps), 0.999) << eps;
}
