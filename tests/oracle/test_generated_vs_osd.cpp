// Our refinement against OpenSubdiv on generated cages that exercise every rule: smooth,
// boundary (all three boundary rules), infinitely sharp and semi-sharp creases (uniform and
// Chaikin), corners, holes, triangles (both triangle rules), n-gons, valence 2 and high valence.
#include <gtest/gtest.h>

#include "common/shapes.h"
#include "osd_reference.h"

using namespace subd2nurbs;
using namespace subd2nurbs::testing;

namespace {

constexpr double kTolerance = 1e-12;  // relative to the bounding-box diagonal (issue #2)

void expect_matches_osd(const MeshInput& m, int levels = 3) {
  OsdComparison c = compare_with_osd(m, levels);
  ASSERT_TRUE(c.osd_accepted);
  EXPECT_EQ(c.count_mismatches, 0) << c.first_problem;
  EXPECT_EQ(c.unmapped, 0) << c.first_problem;
  EXPECT_EQ(c.face_mismatches, 0) << c.first_problem;
  EXPECT_EQ(c.sharpness_mismatches, 0) << c.first_problem;
  EXPECT_EQ(c.hole_mismatches, 0) << c.first_problem;
  EXPECT_LE(c.max_relative_error, kTolerance) << c.first_problem;
  const LimitErrors lim = limit_error_vs_osd(m);
  EXPECT_GE(lim.regular, 0.0);
  EXPECT_LE(lim.regular, kTolerance) << "limit positions";
}

MeshInput with_boundary(MeshInput m, BoundaryRule rule) {
  m.options.boundary = rule;
  return m;
}

}  // namespace

TEST(RefineVsOsd, SmoothClosed) {
  expect_matches_osd(cube());
  expect_matches_osd(torus(7, 5));
}

TEST(RefineVsOsd, BoundaryRules) {
  for (BoundaryRule b : {BoundaryRule::None, BoundaryRule::EdgeOnly, BoundaryRule::EdgeAndCorner})
    expect_matches_osd(with_boundary(grid(4, 3), b));
}

TEST(RefineVsOsd, NgonsAndHighValence) {
  for (int n : {3, 5, 8, 13}) expect_matches_osd(star(n));
}

TEST(RefineVsOsd, SemiSharpCreasesUniformAndChaikin) {
  for (CreaseMethod method : {CreaseMethod::Uniform, CreaseMethod::Chaikin}) {
    MeshInput m = torus(8, 6);
    m.options.crease_method = method;
    // A crease loop around the tube with varying sharpness, plus a branch.
    const int nv = 6;
    double s[] = {0.3, 1.2, 2.7, 0.9, 1.0, 3.4};
    for (int j = 0; j < nv; ++j) m.creases.push_back({2 * nv + j, 2 * nv + (j + 1) % nv, s[j]});
    m.creases.push_back({2 * nv, 3 * nv, 0.2});
    m.creases.push_back({3 * nv, 4 * nv, 1.5});
    m.corners.push_back({5 * nv + 2, 1.7});
    m.corners.push_back({6 * nv + 3, 0.4});
    expect_matches_osd(m, 4);
  }
}

TEST(RefineVsOsd, InfiniteCreasesAndCorners) {
  MeshInput m = grid(5, 4);
  for (int i = 0; i < 5; ++i) m.creases.push_back({6 * 2 + i, 6 * 2 + i + 1, kInfiniteSharpness});
  m.creases.push_back({2, 8, 12.0});
  m.corners.push_back({9, kInfiniteSharpness});
  expect_matches_osd(m);
}

TEST(RefineVsOsd, Holes) {
  MeshInput m = grid(4, 4);
  m.holes = {5, 6};
  expect_matches_osd(m);
}

TEST(RefineVsOsd, TrianglesBothRules) {
  for (TriangleRule t : {TriangleRule::Catmark, TriangleRule::Smooth}) {
    MeshInput m;  // octahedron
    m.positions = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (auto f : std::vector<std::array<int, 3>>{{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                                                   {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}})
      add_face(m, {f[0], f[1], f[2]});
    m.options.triangles = t;
    expect_matches_osd(m);
  }
}

TEST(RefineVsOsd, TrianglesAndPentagonsAveragingFourCorners) {
  // A cube with its bottom split into two triangles and a vertex added on the top-back edge
  // (two pentagons): 28 corners on 7 faces, as if all were quads. Such cages were once taken
  // for all-quad meshes (PolyMesh::build), with wrong connectivity.
  MeshInput m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}, {0.5, 1, 1}};
  add_face(m, {0, 3, 2});
  add_face(m, {0, 2, 1});
  add_face(m, {4, 5, 6, 8, 7});
  add_face(m, {0, 1, 5, 4});
  add_face(m, {1, 2, 6, 5});
  add_face(m, {2, 3, 7, 8, 6});
  add_face(m, {3, 0, 4, 7});
  ASSERT_EQ(m.face_indices.size(), 4 * m.face_sizes.size());
  expect_matches_osd(m);
}

TEST(RefineVsOsd, ValenceTwo) {
  expect_matches_osd(cube_with_valence_two_vertex());
}

// At darts and smooth valence-2 vertices OpenSubdiv's Limit() is an approximation whose error
// shrinks as it is applied deeper; our exact limit must be what it converges to.
TEST(LimitVsOsd, DartAndValenceTwoConvergeToOurExactLimit) {
  MeshInput dart = grid(5, 4);
  dart.creases.push_back({2, 8, kInfiniteSharpness});  // vertex 8: interior, one sharp edge
  MeshInput val2 = cube_with_valence_two_vertex();
  for (const MeshInput& m : {dart, val2}) {
    std::vector<double> err;
    for (int extra = 0; extra <= 5; ++extra) err.push_back(limit_error_vs_osd(m, extra).special);
    ASSERT_GT(err[0], 0.0) << "the shape must have a special vertex";
    for (size_t i = 1; i < err.size(); ++i) EXPECT_LT(err[i], 0.75 * err[i - 1]) << i;
    EXPECT_LT(err.back(), 0.05 * err.front());
    std::printf("OpenSubdiv Limit() error at the special vertex, levels +0..+5: %.3g .. %.3g\n", err.front(), err.back());
  }
}
