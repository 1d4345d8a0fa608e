// Exact identities of refinement that need no oracle: partition of unity, affine invariance,
// the directly built child connectivity equals a fresh build from its face list, stencil
// composition equals level-by-level application.
#include <gtest/gtest.h>

#include <cmath>

#include "common/shapes.h"
#include "core/refine/refiner.h"

using namespace subd2nurbs;
using namespace subd2nurbs::testing;

namespace {

/// Cages covering every rule: creases, corners, boundaries, holes, n-gons, triangles.
std::vector<MeshInput> rule_cages() {
  std::vector<MeshInput> out;
  out.push_back(cube());
  out.push_back(star(7));
  MeshInput g = grid(4, 3);
  g.creases.push_back({6, 7, 1.6});
  g.creases.push_back({7, 8, 0.4});
  g.corners.push_back({12, 2.2});
  g.holes.push_back(4);
  out.push_back(g);
  MeshInput t = torus(6, 5);
  t.options.crease_method = CreaseMethod::Chaikin;
  for (int j = 0; j < 5; ++j) t.creases.push_back({10 + j, 10 + (j + 1) % 5, 0.5 + 0.7 * j});
  out.push_back(t);
  MeshInput e = grid(2, 2);
  e.options.boundary = BoundaryRule::EdgeOnly;
  out.push_back(e);
  return out;
}

std::vector<Point3> points(const MeshInput& m) { return {m.positions.begin(), m.positions.end()}; }

}  // namespace

TEST(RefineIdentities, StencilRowsSumToOne) {
  for (const MeshInput& m : rule_cages()) {
    Refinement r = refine_uniform(SubdivLevel::from_input(m), 3);
    for (const StencilTable& s : r.steps)
      for (int row = 0; row < s.num_rows(); ++row) ASSERT_NEAR(s.row_sum(row), 1.0, 1e-14) << row;
    StencilTable base = r.stencils_from_base(3);
    for (int row = 0; row < base.num_rows(); ++row) ASSERT_NEAR(base.row_sum(row), 1.0, 1e-13);
    StencilTable lim = limit_stencils(r.levels[0]);
    for (int row = 0; row < lim.num_rows(); ++row) ASSERT_NEAR(lim.row_sum(row), 1.0, 1e-13);
  }
}

TEST(RefineIdentities, CommutesWithAffineMaps) {
  // x -> A x + b with a generic (non-orthogonal) A.
  const double A[3][3] = {{1.3, -0.4, 0.2}, {0.5, 0.9, -1.1}, {0.1, 0.7, 2.0}};
  const double b[3] = {10.0, -3.0, 0.5};
  auto map = [&](const Point3& p) {
    Point3 q;
    for (int i = 0; i < 3; ++i) q[i] = A[i][0] * p[0] + A[i][1] * p[1] + A[i][2] * p[2] + b[i];
    return q;
  };
  for (const MeshInput& m : rule_cages()) {
    Refinement r = refine_uniform(SubdivLevel::from_input(m), 2);
    std::vector<Point3> base = points(m), mapped;
    for (const Point3& p : base) mapped.push_back(map(p));
    auto a = r.positions(base), c = r.positions(mapped);
    for (size_t v = 0; v < a[2].size(); ++v) {
      Point3 expect = map(a[2][v]);
      for (int k = 0; k < 3; ++k) ASSERT_NEAR(c[2][v][k], expect[k], 1e-12 * 20);
    }
  }
}

TEST(RefineIdentities, ChildConnectivityEqualsFreshBuild) {
  for (const MeshInput& m : rule_cages()) {
    RefinementStep s = refine_once(SubdivLevel::from_input(m));
    const PolyMesh& c = s.child.mesh;
    std::vector<int> sizes(c.num_faces()), idx;
    for (int f = 0; f < c.num_faces(); ++f) {
      sizes[f] = c.face_size(f);
      idx.insert(idx.end(), c.face_vertices(f), c.face_vertices(f) + c.face_size(f));
    }
    PolyMesh fresh = PolyMesh::build(c.num_vertices(), sizes, idx);
    ASSERT_EQ(fresh.num_edges(), c.num_edges());
    for (int h = 0; h < c.num_corners(); ++h) {
      ASSERT_EQ(fresh.twin(h), c.twin(h)) << h;
      // Edges are numbered differently; compare them through their end vertices.
      const int e = c.corner_edge(h), fe = fresh.corner_edge(h);
      ASSERT_EQ(std::minmax(c.edge_vertex(e, 0), c.edge_vertex(e, 1)),
                std::minmax(fresh.edge_vertex(fe, 0), fresh.edge_vertex(fe, 1)));
    }
    for (int v = 0; v < c.num_vertices(); ++v) {
      ASSERT_EQ(fresh.vertex_face_count(v), c.vertex_face_count(v));
      ASSERT_EQ(fresh.is_boundary_vertex(v), c.is_boundary_vertex(v)) << v;
      // Same fan up to rotation (and identical start on the boundary).
      const int n = c.vertex_face_count(v);
      int shift = 0;
      while (shift < n && fresh.vertex_corners(v)[shift] != c.vertex_corners(v)[0]) ++shift;
      ASSERT_LT(shift, n);
      if (c.is_boundary_vertex(v)) ASSERT_EQ(shift, 0);
      for (int i = 0; i < n; ++i) ASSERT_EQ(fresh.vertex_corners(v)[(shift + i) % n], c.vertex_corners(v)[i]);
    }
  }
}

TEST(RefineIdentities, ComposedStencilsEqualLevelByLevel) {
  for (const MeshInput& m : rule_cages()) {
    Refinement r = refine_uniform(SubdivLevel::from_input(m), 3);
    auto levels = r.positions(points(m));
    std::vector<Point3> direct;
    r.stencils_from_base(3).apply(points(m), direct);
    ASSERT_EQ(direct.size(), levels[3].size());
    for (size_t v = 0; v < direct.size(); ++v)
      for (int k = 0; k < 3; ++k) ASSERT_NEAR(direct[v][k], levels[3][v][k], 1e-13);
  }
}

TEST(RefineIdentities, LimitOfRegularGridIsBSplineValue) {
  // On a regular interior vertex the limit is the bicubic B-spline at the knot:
  // (1/36) [1 4 1]^T [1 4 1] applied to the 3x3 neighbourhood (MATH.md 1.4, n = 4).
  MeshInput g = grid(4, 4);
  StencilTable lim = limit_stencils(SubdivLevel::from_input(g));
  std::vector<Point3> out;
  lim.apply(points(g), out);
  const int v = 2 * 5 + 2;  // interior vertex (2,2)
  Point3 expect{0, 0, 0};
  const double w[3] = {1, 4, 1};
  for (int dj = -1; dj <= 1; ++dj)
    for (int di = -1; di <= 1; ++di)
      for (int k = 0; k < 3; ++k) expect[k] += w[di + 1] * w[dj + 1] / 36.0 * g.positions[v + dj * 5 + di][k];
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(out[v][k], expect[k], 1e-15);
}

TEST(RefineIdentities, RingEigenvectorReproducesClosedFormSmoothMask) {
  // MATH.md 1.4: p = (n^2 v + 4 sum e + sum d) / (n (n + 5)).
  for (int n = 3; n <= 12; ++n) {
    std::vector<double> w = ring_limit_weights(n, -1);
    const double den = n * (n + 5.0);
    EXPECT_NEAR(w[0], n * n / den, 1e-14) << n;
    for (int r = 0; r < n; ++r) {
      EXPECT_NEAR(w[1 + r], 4 / den, 1e-14);
      EXPECT_NEAR(w[1 + n + r], 1 / den, 1e-14);
    }
  }
}
