// gather_quad_grid on a planar integer lattice, where every B-spline point of a quad's 4 x 4
// grid is a lattice point: a real point is the cage vertex there, and a phantom (the reflection
// 2 a - b across a boundary or infinitely sharp side) is the lattice point beyond the side,
// exactly. So every gathered point must be the lattice point of its grid position, with the
// cage vertex where one exists on the open side and -1 (phantom) across sharp and boundary sides.
#include <gtest/gtest.h>

#include "common/shapes.h"
#include "core/refine/quad_grid.h"

namespace subd2nurbs {
namespace {

constexpr int kN = 5;  // 5 x 5 quads, vertex (i, j) at index j * 6 + i, position (i, j, 0)

MeshInput lattice() {
  MeshInput m = testing::grid(kN, kN);
  for (auto& p : m.positions) p[2] = 0;
  return m;
}

/// Checks every quad of `level` against the lattice; `crease_y`: the lattice line y = crease_y
/// is infinitely sharp (-1: none).
void expect_lattice_grids(const SubdivLevel& level, const std::vector<Point3>& P, int crease_y, bool diagonals) {
  const PolyMesh& m = level.mesh;
  for (int f = 0; f < m.num_faces(); ++f) {
    const int i0 = f % kN, j0 = f / kN;  // the face's corner 0 is vertex (i0, j0)
    // A side is open when the face across it exists and the side is not on the crease line.
    const bool open[4] = {j0 > 0 && j0 != crease_y, i0 < kN - 1, j0 < kN - 1 && j0 + 1 != crease_y, i0 > 0};
    bool diagonal[4];
    for (int k = 0; k < 4; ++k) diagonal[k] = diagonals && open[k] && open[(k + 3) % 4];
    QuadGrid g;
    gather_quad_grid(level, P, f, diagonal, g);
    for (int gi = -1; gi <= 2; ++gi)
      for (int gj = -1; gj <= 2; ++gj) {
        const bool corner_point = (gi == -1 || gi == 2) && (gj == -1 || gj == 2);
        const bool across_j = gj == -1 ? !open[0] : gj == 2 ? !open[2] : false;  // beyond a closed side
        const bool across_i = gi == -1 ? !open[3] : gi == 2 ? !open[1] : false;
        if (corner_point && !diagonals && !across_i && !across_j) {
          EXPECT_FALSE(g.has(gi, gj)) << "face " << f << " (" << gi << ", " << gj << "): no diagonal was asked for";
          continue;
        }
        ASSERT_TRUE(g.has(gi, gj)) << "face " << f << " (" << gi << ", " << gj << ")";
        const Point3 expect{double(i0 + gi), double(j0 + gj), 0.0};
        EXPECT_EQ(g.at(gi, gj), expect) << "face " << f << " (" << gi << ", " << gj << ")";
        const int vertex = across_i || across_j ? -1 : (j0 + gj) * (kN + 1) + (i0 + gi);
        EXPECT_EQ(g.vertex_at(gi, gj), vertex) << "face " << f << " (" << gi << ", " << gj << ")";
      }
  }
}

TEST(QuadGrid, LatticePointsRealAndPhantomAtBoundaries) {
  const MeshInput in = lattice();
  const std::vector<Point3> P(in.positions.begin(), in.positions.end());
  const SubdivLevel level = SubdivLevel::from_input(in);
  expect_lattice_grids(level, P, -1, true);
  expect_lattice_grids(level, P, -1, false);  // Stam-style corners: the diagonal left out
}

TEST(QuadGrid, PhantomsAcrossAnInfinitelySharpLine) {
  MeshInput in = lattice();
  for (int i = 0; i < kN; ++i) in.creases.push_back({2 * (kN + 1) + i, 2 * (kN + 1) + i + 1, 10.0});  // y = 2
  const std::vector<Point3> P(in.positions.begin(), in.positions.end());
  const SubdivLevel level = SubdivLevel::from_input(in);
  expect_lattice_grids(level, P, 2, true);
}

}  // namespace
}  // namespace subd2nurbs
