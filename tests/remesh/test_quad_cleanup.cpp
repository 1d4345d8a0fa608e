// clean_quad_dominant (core/remesh/quad_cleanup.h) on quad-dominant meshes built here whose
// regular form is known: a flat grid of quads with one edge rotated comes back to the grid (the
// exact edge set of the grid); a grid whose 2 x 1 block is a triangle, a parallelogram and a
// triangle comes back to the grid by a triangle walk and a merge; a feature edge is never rotated;
// on a jittered grid of random quads and triangles with random feature edges the invariants hold:
// the mesh stays manifold and oriented (PolyMesh::build), its vertices, boundary and feature edges
// stay, faces and edges both drop by the merges (Euler characteristic kept), every face stays
// convex, no vertex on a feature edge or the boundary gets more irregular, and the stats' valence
// excess matches an independent recount and drops.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "core/mesh/poly_mesh.h"
#include "core/remesh/quad_cleanup.h"

namespace subd2nurbs {
namespace {

using V3 = Eigen::Vector3d;
using Polys = std::vector<std::vector<int>>;
using Edge = std::pair<int, int>;

struct Grid {
  int nx, ny;
  std::vector<V3> p;
  int v(int i, int j) const { return j * (nx + 1) + i; }
};

Grid make_grid(int nx, int ny) {
  Grid g{nx, ny, {}};
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) g.p.push_back(V3(i, j, 0));
  return g;
}

// The grid's quads, counter-clockwise seen from +z, except the cells in `skip` (i, j).
Polys grid_quads(const Grid& g, const std::set<std::pair<int, int>>& skip = {}) {
  Polys q;
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i)
      if (!skip.count({i, j})) q.push_back({g.v(i, j), g.v(i + 1, j), g.v(i + 1, j + 1), g.v(i, j + 1)});
  return q;
}

std::set<Edge> edges_of(const Polys& polys) {
  std::set<Edge> e;
  for (const auto& f : polys)
    for (size_t k = 0; k < f.size(); ++k) {
      int a = f[k], b = f[(k + 1) % f.size()];
      e.insert({std::min(a, b), std::max(a, b)});
    }
  return e;
}

std::vector<char> grid_corners(const Grid& g) {
  std::vector<char> c(g.p.size(), 0);
  c[g.v(0, 0)] = c[g.v(g.nx, 0)] = c[g.v(0, g.ny)] = c[g.v(g.nx, g.ny)] = 1;
  return c;
}

// Independent recount of the split cage's valence excess and irregular vertices (as the
// remesher's statistics count them: corners excluded, each polygon's centre |size - 4|).
std::pair<int, int> recount(const Polys& polys, int n, const std::vector<char>& corner) {
  std::vector<int> sizes, indices;
  for (const auto& f : polys) {
    sizes.push_back(static_cast<int>(f.size()));
    indices.insert(indices.end(), f.begin(), f.end());
  }
  PolyMesh pm = PolyMesh::build(n, sizes, indices);
  int excess = 0, irregular = 0;
  for (int v = 0; v < n; ++v) {
    if (pm.is_unused_vertex(v) || corner[v]) continue;
    int e = std::abs(pm.valence(v) - (pm.is_boundary_vertex(v) ? 3 : 4));
    excess += e;
    irregular += e > 0;
  }
  for (int s : sizes) {
    excess += std::abs(s - 4);
    irregular += s != 4;
  }
  return {excess, irregular};
}

// Per vertex |valence - regular| (corners 0), counted on the mesh.
std::vector<int> vertex_excess(const Polys& polys, int n, const std::vector<char>& corner) {
  std::vector<int> sizes, indices;
  for (const auto& f : polys) {
    sizes.push_back(static_cast<int>(f.size()));
    indices.insert(indices.end(), f.begin(), f.end());
  }
  PolyMesh pm = PolyMesh::build(n, sizes, indices);
  std::vector<int> e(n, 0);
  for (int v = 0; v < n; ++v)
    if (!pm.is_unused_vertex(v) && !corner[v]) e[v] = std::abs(pm.valence(v) - (pm.is_boundary_vertex(v) ? 3 : 4));
  return e;
}

// The smallest corner sine over the faces (normal +z); only at the vertices marked in `at` if given.
double worst_corner(const Polys& polys, const std::vector<V3>& p, const std::vector<char>* at = nullptr) {
  double worst = 1;
  for (const auto& f : polys)
    for (size_t k = 0; k < f.size(); ++k) {
      const size_t m = f.size();
      if (at && !(*at)[f[k]]) continue;
      V3 a = p[f[(k + 1) % m]] - p[f[k]], b = p[f[(k + m - 1) % m]] - p[f[k]];
      worst = std::min(worst, a.cross(b).z() / (a.norm() * b.norm()));
    }
  return worst;
}

const std::function<bool(int, int)> kNoFeature = [](int, int) { return false; };

TEST(QuadCleanup, RotatedEdgeComesBackToTheGrid) {
  Grid g = make_grid(6, 5);
  // the 2 x 1 block of cells (2,2), (3,2): its middle vertices pushed out so that the hexagon is
  // convex and its other splits are valid quads too
  const int p0 = g.v(2, 2), p1 = g.v(3, 2), p2 = g.v(4, 2), p3 = g.v(2, 3), p4 = g.v(3, 3), p5 = g.v(4, 3);
  g.p[p1].y() = 1.7;
  g.p[p4].y() = 3.3;
  const Polys grid = grid_quads(g);
  Polys polys = grid_quads(g, {{2, 2}, {3, 2}});
  polys.push_back({p0, p1, p2, p5});  // rotated: the diagonal p0-p5 instead of p1-p4
  polys.push_back({p5, p4, p3, p0});
  const std::vector<V3> normals(g.p.size(), V3(0, 0, 1));
  const std::vector<char> corner = grid_corners(g);
  ASSERT_EQ(recount(polys, int(g.p.size()), corner), std::make_pair(4, 4));  // p0, p5 of valence 5, p1, p4 of 3
  QuadCleanupStats st = clean_quad_dominant(polys, g.p, normals, corner, kNoFeature);
  EXPECT_EQ(st.excess_before, 4);
  EXPECT_EQ(st.irregular_before, 4);
  EXPECT_EQ(st.excess_after, 0);
  EXPECT_EQ(st.irregular_after, 0);
  EXPECT_EQ(st.rotations, 1);
  EXPECT_EQ(st.merges, 0);
  EXPECT_EQ(edges_of(polys), edges_of(grid));
  EXPECT_EQ(recount(polys, int(g.p.size()), corner), std::make_pair(0, 0));

  // the same with the rotated diagonal a feature edge: it stays, and so does every face
  Polys fixed = grid_quads(g, {{2, 2}, {3, 2}});
  fixed.push_back({p0, p1, p2, p5});
  fixed.push_back({p5, p4, p3, p0});
  const Polys before = fixed;
  auto feature = [&](int a, int b) { return std::minmax(a, b) == std::minmax(p0, p5); };
  st = clean_quad_dominant(fixed, g.p, normals, corner, feature);
  EXPECT_TRUE(edges_of(fixed).count(std::minmax(p0, p5)));
  EXPECT_EQ(fixed, before);
  EXPECT_EQ(st.excess_after, st.excess_before);
}

TEST(QuadCleanup, TrianglesWalkMeetAndMergeIntoTheGrid) {
  Grid g = make_grid(6, 5);
  const int p0 = g.v(2, 2), p1 = g.v(3, 2), p2 = g.v(4, 2), p3 = g.v(2, 3), p4 = g.v(3, 3), p5 = g.v(4, 3);
  const Polys grid = grid_quads(g);
  // the block as a triangle, a parallelogram and a triangle: two triangles a quad apart
  Polys polys = grid_quads(g, {{2, 2}, {3, 2}});
  polys.push_back({p0, p1, p3});
  polys.push_back({p1, p2, p4, p3});
  polys.push_back({p2, p5, p4});
  const std::vector<V3> normals(g.p.size(), V3(0, 0, 1));
  const std::vector<char> corner = grid_corners(g);
  // p2 and p3 of valence 5, two triangle centres of valence 3
  ASSERT_EQ(recount(polys, int(g.p.size()), corner), std::make_pair(4, 4));
  const int faces_before = static_cast<int>(polys.size());
  QuadCleanupStats st = clean_quad_dominant(polys, g.p, normals, corner, kNoFeature);
  EXPECT_EQ(st.merges, 1);
  EXPECT_GE(st.walks, 1);
  EXPECT_EQ(static_cast<int>(polys.size()), faces_before - 1);
  EXPECT_EQ(st.excess_after, 0);
  EXPECT_EQ(edges_of(polys), edges_of(grid));
  for (const auto& f : polys) EXPECT_EQ(f.size(), 4u);

  // without walks the single rotations cannot lower the excess here: nothing changes
  Polys still = grid_quads(g, {{2, 2}, {3, 2}});
  still.push_back({p0, p1, p3});
  still.push_back({p1, p2, p4, p3});
  still.push_back({p2, p5, p4});
  QuadCleanupOptions no_walks;
  no_walks.walk_depth = 0;
  st = clean_quad_dominant(still, g.p, normals, corner, kNoFeature, no_walks);
  EXPECT_EQ(st.excess_after, 4);
  EXPECT_EQ(st.merges, 0);
}

// A jittered 14 x 12 grid, each cell a quad or two triangles (random diagonal), random interior
// edges tagged as features: the invariants of the pass.
TEST(QuadCleanup, InvariantsOnRandomQuadDominantMeshes) {
  for (std::uint32_t seed : {1u, 7u, 42u}) {
    std::uint32_t state = seed;
    auto rnd = [&]() {
      state = state * 1664525u + 1013904223u;
      return (state >> 8) / double(1u << 24);
    };
    Grid g = make_grid(14, 12);
    for (int j = 1; j < g.ny; ++j)
      for (int i = 1; i < g.nx; ++i) g.p[g.v(i, j)] += V3(0.2 * (rnd() - 0.5), 0.2 * (rnd() - 0.5), 0);
    Polys polys;
    for (int j = 0; j < g.ny; ++j)
      for (int i = 0; i < g.nx; ++i) {
        int a = g.v(i, j), b = g.v(i + 1, j), c = g.v(i + 1, j + 1), d = g.v(i, j + 1);
        double r = rnd();
        if (r < 0.5)
          polys.push_back({a, b, c, d});
        else if (r < 0.75)
          polys.push_back({a, b, c}), polys.push_back({a, c, d});
        else
          polys.push_back({a, b, d}), polys.push_back({b, c, d});
      }
    std::set<Edge> features;
    for (const Edge& e : edges_of(polys))
      if (rnd() < 0.25) features.insert(e);
    auto is_feature = [&](int a, int b) { return features.count(std::minmax(a, b)) > 0; };
    const int n = static_cast<int>(g.p.size());
    const std::vector<V3> normals(n, V3(0, 0, 1));
    const std::vector<char> corner = grid_corners(g);
    const std::set<Edge> edges_before = edges_of(polys);
    const int faces_before = static_cast<int>(polys.size());
    const double worst_before = worst_corner(polys, g.p);
    std::set<Edge> boundary_before;
    {
      std::vector<int> sizes, idx;
      for (const auto& f : polys) sizes.push_back(int(f.size())), idx.insert(idx.end(), f.begin(), f.end());
      PolyMesh pm = PolyMesh::build(n, sizes, idx);
      for (const Edge& e : edges_before)
        if (pm.is_boundary_edge(pm.find_edge(e.first, e.second)))
          boundary_before.insert(e);
    }
    const auto energy_before = recount(polys, n, corner);
    // vertices on a feature edge or the boundary: never more irregular, corners there no sharper
    // than min(curve_sine, the sharpest before)
    std::vector<char> on_curve(n, 0);
    for (const Edge& e : features) on_curve[e.first] = on_curve[e.second] = 1;
    for (const Edge& e : boundary_before) on_curve[e.first] = on_curve[e.second] = 1;
    const std::vector<int> excess_before = vertex_excess(polys, n, corner);
    const double curve_worst_before = worst_corner(polys, g.p, &on_curve);
    QuadCleanupStats st = clean_quad_dominant(polys, g.p, normals, corner, is_feature);
    SCOPED_TRACE("seed " + std::to_string(seed));
    // manifold and oriented, every vertex still used
    std::vector<int> sizes, idx;
    for (const auto& f : polys) sizes.push_back(int(f.size())), idx.insert(idx.end(), f.begin(), f.end());
    PolyMesh pm = PolyMesh::build(n, sizes, idx);
    for (int v = 0; v < n; ++v) EXPECT_FALSE(pm.is_unused_vertex(v)) << v;
    // Euler characteristic: faces and edges both fewer by the merges
    const std::set<Edge> edges_after = edges_of(polys);
    EXPECT_EQ(static_cast<int>(polys.size()), faces_before - st.merges);
    EXPECT_EQ(edges_after.size(), edges_before.size() - st.merges);
    // boundary and features kept
    for (const Edge& e : boundary_before) {
      ASSERT_GE(pm.find_edge(e.first, e.second), 0);
      EXPECT_TRUE(pm.is_boundary_edge(pm.find_edge(e.first, e.second)));
    }
    for (const Edge& e : features) EXPECT_TRUE(edges_after.count(e)) << e.first << "-" << e.second;
    // faces convex, no worse than the worst before or the pass's minimum sine
    EXPECT_GE(worst_corner(polys, g.p), std::min(worst_before, 0.2) - 1e-12);
    for (int s : sizes) EXPECT_TRUE(s == 3 || s == 4);
    const std::vector<int> excess_after = vertex_excess(polys, n, corner);
    for (int v = 0; v < n; ++v)
      if (on_curve[v]) EXPECT_LE(excess_after[v], excess_before[v]) << "vertex " << v;
    EXPECT_GE(worst_corner(polys, g.p, &on_curve), std::min(curve_worst_before, QuadCleanupOptions{}.curve_sine) - 1e-12);
    // the stats against an independent recount; the excess drops
    EXPECT_EQ(std::make_pair(st.excess_before, st.irregular_before), energy_before);
    EXPECT_EQ(std::make_pair(st.excess_after, st.irregular_after), recount(polys, n, corner));
    EXPECT_LT(st.excess_after, st.excess_before);
    EXPECT_GT(st.rotations + st.merges, 0);
    std::printf("  seed %u: %d faces, excess %d -> %d, irregular %d -> %d, %d rotations, %d merges, %d walks\n", seed,
                faces_before, st.excess_before, st.excess_after, st.irregular_before, st.irregular_after, st.rotations,
                st.merges, st.walks);
  }
}

}  // namespace
}  // namespace subd2nurbs
