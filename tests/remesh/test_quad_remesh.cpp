// quad_remesh on analytic meshes: the cage is all quads, manifold and oriented (PolyMesh::build),
// with the input's Euler characteristic, boundary loops and components per component (counted
// here independently of the remesher); the box's 12 edges and the drilled box's circles are
// covered by tagged cage edges lying on them, the 8 corners are cage corners; the face count is
// near the target; the result is deterministic.
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numeric>
#include <random>
#include <set>
#include <string>

#include "core/mesh/poly_mesh.h"
#include "core/remesh/quad_remesh.h"
#include "core/util/error.h"
#include "core/util/parallel.h"
#include "io/cage_reader.h"
#include "remesh/test_meshes.h"

namespace subd2nurbs {
namespace {

using test::P3;

// Per component (Euler characteristic, boundary loops), sorted.
std::vector<std::pair<int, int>> components(const MeshInput& m) {
  int n = m.num_vertices();
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  std::function<int(int)> root = [&](int x) { return parent[x] == x ? x : parent[x] = root(parent[x]); };
  std::map<std::pair<int, int>, int> edge_count;
  std::vector<int> first;
  int begin = 0;
  std::set<int> used;
  for (int size : m.face_sizes) {
    first.push_back(m.face_indices[begin]);
    for (int k = 0; k < size; ++k) {
      int a = m.face_indices[begin + k], b = m.face_indices[begin + (k + 1) % size];
      used.insert(a);
      parent[root(a)] = root(b);
      edge_count[{std::min(a, b), std::max(a, b)}]++;
    }
    begin += size;
  }
  std::map<int, int> euler, loops;
  for (int v : used) euler[root(v)]++;
  for (int f : first) euler[root(f)]++;
  std::vector<int> bparent(n);
  std::iota(bparent.begin(), bparent.end(), 0);
  std::function<int(int)> broot = [&](int x) { return bparent[x] == x ? x : bparent[x] = broot(bparent[x]); };
  std::set<int> on_boundary;
  for (const auto& [e, c] : edge_count) {
    euler[root(e.first)]--;
    if (c == 1) {
      bparent[broot(e.first)] = broot(e.second);
      on_boundary.insert(e.first);
      on_boundary.insert(e.second);
    }
  }
  for (int v : on_boundary)
    if (broot(v) == v) loops[root(v)]++;
  std::vector<std::pair<int, int>> out;
  for (const auto& [r, e] : euler) out.push_back({e, loops[r]});
  std::sort(out.begin(), out.end());
  return out;
}

// The coordinates in which the cage edge a - b lies on one face plane (+-1) of the cube [-1, 1]^3:
// 2 along one of its twelve edges.
int cube_planes_of_edge(const P3& a, const P3& b) {
  int fixed = 0;
  for (int k = 0; k < 3; ++k) fixed += std::abs(std::abs(a[k]) - 1) < 1e-9 && std::abs(a[k] - b[k]) < 1e-9;
  return fixed;
}

// The checks every cage must pass.
void check_cage(const MeshInput& input, const QuadRemeshResult& r, int target) {
  const MeshInput& cage = r.cage;
  ASSERT_FALSE(r.cancelled);
  ASSERT_GT(cage.num_faces(), 0);
  for (int s : cage.face_sizes) ASSERT_EQ(s, 4);
  PolyMesh pm = PolyMesh::build(cage.num_vertices(), cage.face_sizes, cage.face_indices);
  EXPECT_EQ(components(cage), components(input));
  for (const auto& c : cage.creases) {
    EXPECT_GE(pm.find_edge(c.v0, c.v1), 0) << c.v0 << "-" << c.v1;
    EXPECT_EQ(c.sharpness, kInfiniteSharpness);
  }
  for (const auto& c : cage.corners) EXPECT_EQ(c.sharpness, kInfiniteSharpness);
  if (target > 0) {
    EXPECT_GT(cage.num_faces(), target / 1.5);
    EXPECT_LT(cage.num_faces(), target * 1.5);
  }
  // the orientation follows the input's: the cage of a closed outward mesh encloses positive volume
  double volume = 0;
  for (int f = 0; f < cage.num_faces(); ++f) {
    const int* q = &cage.face_indices[4 * f];
    for (int k = 1; k < 3; ++k) {
      const P3 &a = cage.positions[q[0]], &b = cage.positions[q[k]], &c = cage.positions[q[k + 1]];
      volume += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
    }
  }
  if (r.stats.boundaries_input == 0) {
    EXPECT_GT(volume, 0);
  }
  const QuadRemeshStats& s = r.stats;
  std::printf("  faces %d vertices %d extraordinary %d (%.1f%%) feature edges %d corners %d chains %d/%d "
              "coarse quads %d triangles %d dense vertices %d field %.3f s extract %.3f s\n",
              s.faces, s.vertices, s.extraordinary_vertices, 100.0 * s.extraordinary_vertices / s.vertices,
              s.feature_edges, s.corners, s.feature_chains_kept, s.feature_chains_in, s.coarse_quads,
              s.coarse_triangles, s.dense_vertices, s.field_seconds, s.extract_seconds);
  EXPECT_EQ(s.faces, cage.num_faces());
  EXPECT_EQ(s.euler_cage, s.euler_input);
  EXPECT_EQ(s.boundaries_cage, s.boundaries_input);
  EXPECT_EQ(s.components_cage, s.components_input);
}

QuadRemeshResult remesh(const MeshInput& m, int target) {
  QuadRemeshOptions o;
  o.target_faces = target;
  return quad_remesh(m, o);
}

// The remesh of m at `target` quads with the option `flag` off and then on (the other options
// as in o), both cages checked (check_cage; count_checked: their face counts within 1.5x of the
// target too): what a step's own test compares.
struct OffOn {
  QuadRemeshResult off, on;
};
OffOn off_and_on(const MeshInput& m, QuadRemeshOptions o, bool QuadRemeshOptions::*flag, int target,
                 bool count_checked = true) {
  o.target_faces = target;
  OffOn r;
  o.*flag = false;
  r.off = quad_remesh(m, o);
  o.*flag = true;
  r.on = quad_remesh(m, o);
  check_cage(m, r.off, count_checked ? target : 0);
  check_cage(m, r.on, count_checked ? target : 0);
  return r;
}

double radius(const std::array<double, 3>& p) { return std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]); }

TEST(QuadRemesh, SphereKeepsTopologyAndLiesOnTheSphere) {
  MeshInput m = test::icosphere(4);
  QuadRemeshResult r = remesh(m, 300);
  check_cage(m, r, 300);
  EXPECT_TRUE(r.cage.creases.empty());
  EXPECT_TRUE(r.cage.corners.empty());
  // every cage vertex on the input (the icosphere's chords lie within 1 - cos of its edge angle)
  for (const auto& p : r.cage.positions) {
    EXPECT_LT(radius(p), 1 + 1e-9);
    EXPECT_GT(radius(p), 0.99);
  }
}

TEST(QuadRemesh, TorusKeepsGenusOne) {
  MeshInput m = test::torus(2, 0.7, 90, 36);
  QuadRemeshResult r = remesh(m, 400);
  check_cage(m, r, 400);
  EXPECT_EQ(r.stats.euler_cage, 0);
}

TEST(QuadRemesh, OpenCylinderKeepsItsTwoBoundaries) {
  MeshInput m = test::open_cylinder(1, 2, 64, 24);
  QuadRemeshResult r = remesh(m, 200);
  check_cage(m, r, 200);
  EXPECT_EQ(r.stats.boundaries_cage, 2);
  for (const auto& p : r.cage.positions) EXPECT_NEAR(std::hypot(p[0], p[1]), 1.0, 0.01);
}

TEST(QuadRemesh, FlatSquareStaysFlatWithItsCornersAndBoundary) {
  test::MeshBuilder b;
  b.patch([](double u, double v) { return P3{2 * u - 1, 2 * v - 1, 0}; }, 20, 20);
  MeshInput m = b.mesh();
  QuadRemeshResult r = remesh(m, 100);
  check_cage(m, r, 100);
  EXPECT_EQ(r.stats.boundaries_cage, 1);
  for (const auto& p : r.cage.positions) EXPECT_EQ(p[2], 0.0);
  double perimeter = 0;
  for (const auto& c : r.cage.creases) {
    const P3 &a = r.cage.positions[c.v0], &e = r.cage.positions[c.v1];
    EXPECT_TRUE((std::abs(a[0]) == 1 && a[0] == e[0]) || (std::abs(a[1]) == 1 && a[1] == e[1])) << "tagged edge off the boundary";
    perimeter += std::hypot(a[0] - e[0], a[1] - e[1]);
  }
  EXPECT_NEAR(perimeter, 8.0, 1e-12);
  std::set<std::array<double, 3>> corners;
  for (const auto& c : r.cage.corners) corners.insert(r.cage.positions[c.vertex]);
  EXPECT_EQ(corners, (std::set<std::array<double, 3>>{{-1, -1, 0}, {1, -1, 0}, {-1, 1, 0}, {1, 1, 0}}));
}

TEST(QuadRemesh, TwoSpheresStayTwoComponents) {
  MeshInput m = test::concat(test::icosphere(3), test::icosphere(3, 0.5, {3, 0, 0}));
  QuadRemeshResult r = remesh(m, 250);
  check_cage(m, r, 250);
  EXPECT_EQ(r.stats.components_cage, 2);
}

TEST(QuadRemesh, ComponentsSmallerThanTheSpacingKeepTheirTopology) {
  // a sphere of radius 0.05 and a small torus beside a sphere of radius 1: tiny closed cages
  MeshInput m = test::concat(test::icosphere(3), test::icosphere(2, 0.05, {3, 0, 0}));
  m = test::concat(m, test::torus(0.1, 0.03, 24, 16));
  QuadRemeshResult r = remesh(m, 200);
  check_cage(m, r, 0);
  EXPECT_EQ(r.stats.components_cage, 3);
}

// The box's edges: every tagged cage edge lies on one analytic edge, and on each of the 12 the
// tagged edges add up to its length; the 8 corners are cage corners.
TEST(QuadRemesh, BoxKeepsItsEdgesAndCorners) {
  MeshInput m = test::box(16);
  QuadRemeshResult r = remesh(m, 300);
  check_cage(m, r, 300);
  EXPECT_EQ(r.features.edges.size(), 12u * 16u);
  EXPECT_EQ(r.features.corners.size(), 8u);
  std::map<std::array<int, 3>, double> length;  // per box edge (the fixed coordinates' signs, 0 for the free)
  for (const auto& c : r.cage.creases) {
    const P3 &a = r.cage.positions[c.v0], &b = r.cage.positions[c.v1];
    std::array<int, 3> key{};
    int fixed = 0;
    for (int k = 0; k < 3; ++k)
      if (std::abs(std::abs(a[k]) - 1) < 1e-9 && std::abs(a[k] - b[k]) < 1e-9) {
        key[k] = a[k] > 0 ? 1 : -1;
        ++fixed;
      }
    EXPECT_EQ(fixed, 2) << "tagged edge off the box's edges";
    length[key] += std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
  }
  EXPECT_EQ(length.size(), 12u);
  for (const auto& [key, l] : length) EXPECT_NEAR(l, 2.0, 1e-9);
  std::set<std::array<double, 3>> corners;
  for (const auto& c : r.cage.corners) corners.insert(r.cage.positions[c.vertex]);
  EXPECT_EQ(corners.size(), 8u);
  for (const auto& p : corners) {
    for (double x : p) EXPECT_EQ(std::abs(x), 1.0);
  }
  // planar faces stay planar: every cage vertex on the box's surface
  for (const auto& p : r.cage.positions)
    EXPECT_NEAR(std::max({std::abs(p[0]), std::abs(p[1]), std::abs(p[2])}), 1.0, 1e-9);
}

TEST(QuadRemesh, DrilledBoxKeepsGenusEdgesAndCircles) {
  const double hole = 0.4;
  MeshInput m = test::drilled_box(hole, 64, 8, 16);
  QuadRemeshResult r = remesh(m, 400);
  check_cage(m, r, 400);
  EXPECT_EQ(r.stats.euler_cage, 0);
  EXPECT_EQ(r.features.corners.size(), 8u);
  EXPECT_EQ(r.features.chains, 14);
  double circle[2] = {0, 0}, box_edges = 0;
  for (const auto& c : r.cage.creases) {
    const P3 &a = r.cage.positions[c.v0], &b = r.cage.positions[c.v1];
    double l = std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
    bool on_circle = std::abs(std::abs(a[2]) - 1) < 1e-9 && a[2] == b[2] && std::abs(std::hypot(a[0], a[1]) - hole) < 0.01 * hole &&
                     std::abs(std::hypot(b[0], b[1]) - hole) < 0.01 * hole;
    if (on_circle) {
      circle[a[2] > 0] += l;
    } else {
      EXPECT_EQ(cube_planes_of_edge(a, b), 2) << "tagged edge neither on a circle nor on a box edge";
      box_edges += l;
    }
  }
  EXPECT_NEAR(box_edges, 24.0, 1e-9);
  for (double c : circle) {
    EXPECT_GT(c, 0.95 * 2 * test::kTestPi * hole);
    EXPECT_LT(c, 2 * test::kTestPi * hole);
  }
  std::set<std::array<double, 3>> corners;
  for (const auto& c : r.cage.corners) corners.insert(r.cage.positions[c.vertex]);
  EXPECT_EQ(corners.size(), 8u);
}

// A rim with tight arcs (fandisk's situation): the slab's rounded corners (radius 0.1) are far
// tighter than the lattice spacing (~0.45), so a coarse feature edge cuts across an arc and the
// quad beside it spans the arc's wall. Every point of the split (edge midpoints, quad centres)
// must land on the face of the part its quad belongs to: each cage quad's four vertices lie on
// one same analytic face (top, bottom or the smooth wall; a rim vertex lies on two). A greedy
// walk towards a wall quad's centre used to stop on the bottom beside it (a quad straddling the
// sharp rim, which the fit then folds). Tagged edges lie on the rims.
TEST(QuadRemesh, QuadsBesideTightArcsStayOnTheirFace) {
  const double rho = 0.1, h = 0.5, tol = 2e-3;
  MeshInput m = test::rounded_slab(rho, h, 256, 12, 16);
  // Without plane edges: they end the walls' flat sides at the arcs (vertical feature lines)
  // and no coarse feature edge would cut across an arc.
  QuadRemeshOptions o;
  o.target_faces = 300;
  o.plane_edges = false;
  QuadRemeshResult r = quad_remesh(m, o);
  check_cage(m, r, 300);
  EXPECT_TRUE(r.features.corners.empty());
  EXPECT_EQ(r.features.chains, 2);
  // distance of (x, y) to the rounded square's outline, signed (negative inside)
  auto outline = [&](const P3& p) {
    const double qx = std::abs(p[0]) - (1 - rho), qy = std::abs(p[1]) - (1 - rho);
    return std::hypot(std::max(qx, 0.0), std::max(qy, 0.0)) + std::min(std::max(qx, qy), 0.0) - rho;
  };
  auto faces = [&](const P3& p) {  // bit 0 top, 1 bottom, 2 wall
    const double d = outline(p);
    int f = 0;
    if (std::abs(p[2] - h) < tol && d < tol) f |= 1;
    if (std::abs(p[2] + h) < tol && d < tol) f |= 2;
    if (std::abs(d) < tol && std::abs(p[2]) < h + tol) f |= 4;
    return f;
  };
  int straddling = 0;
  for (int q = 0; q < r.cage.num_faces(); ++q) {
    int common = 7;
    for (int k = 0; k < 4; ++k) {
      const P3& p = r.cage.positions[r.cage.face_indices[4 * q + k]];
      EXPECT_NE(faces(p), 0) << "cage vertex off the slab: " << p[0] << " " << p[1] << " " << p[2];
      common &= faces(p);
    }
    if (common == 0) {
      ++straddling;
      for (int k = 0; k < 4; ++k) {  // the quad, for the log
        const P3& p = r.cage.positions[r.cage.face_indices[4 * q + k]];
        std::printf("    quad %d v%d (%.4f %.4f %.4f) faces %d outline %.4g\n", q, r.cage.face_indices[4 * q + k], p[0], p[1], p[2], faces(p), outline(p));
      }
    }
  }
  EXPECT_EQ(straddling, 0) << "cage quads whose vertices lie on no one face of the slab";
  for (const auto& c : r.cage.creases)
    for (int v : {c.v0, c.v1}) {
      const P3& p = r.cage.positions[v];
      EXPECT_TRUE(std::abs(std::abs(p[2]) - h) < 1e-12 && std::abs(outline(p)) < tol)
          << "tagged vertex off the rims: " << p[0] << " " << p[1] << " " << p[2];
    }
}

// An ear along a rounded rim (fandisk's bottom rim at --target-faces 300): a coarse triangle
// whose three corners are consecutive vertices of one rim chain (two of its edges rim edges, the
// third a chord of the rim's arc). On the wall side its plane is the cap's and it faces away
// from the wall: its three split quads lie along the sharp edge, folded over onto the cap, and
// the fit turns the normals across the crease by 180 degrees. The oracle is the slab's exact
// geometry: no cage quad may have all four vertices on one rim (the rim of the caps z = +-h at
// the rounded square's outline), and every quad whose vertices all lie on a cap faces that
// cap's normal (+-z) within 60 degrees. This slab (rounded corners of radius 0.25, 12 wall
// layers, 400 quads) made an ear at a bottom arc before the ears were flipped (3 quads along
// the rim).
TEST(QuadRemesh, NoEarAlongARoundedRim) {
  const double rho = 0.25, h = 0.3, tol = 2e-3;
  MeshInput m = test::rounded_slab(rho, h, 128, 12, 12);
  QuadRemeshResult r = remesh(m, 400);
  check_cage(m, r, 400);
  auto outline = [&](const P3& p) {  // signed distance to the rounded square's outline
    const double qx = std::abs(p[0]) - (1 - rho), qy = std::abs(p[1]) - (1 - rho);
    return std::hypot(std::max(qx, 0.0), std::max(qy, 0.0)) + std::min(std::max(qx, qy), 0.0) - rho;
  };
  auto on_cap = [&](const P3& p, double side) { return std::abs(p[2] - side * h) < 1e-9 && outline(p) < tol; };
  auto on_rim = [&](const P3& p, double side) { return on_cap(p, side) && std::abs(outline(p)) < tol; };
  int along_rim = 0, facing_away = 0, on_caps = 0;
  for (int q = 0; q < r.cage.num_faces(); ++q) {
    P3 c[4];
    for (int k = 0; k < 4; ++k) c[k] = r.cage.positions[r.cage.face_indices[4 * q + k]];
    for (double side : {-1.0, 1.0}) {
      bool rim = true, cap = true;
      for (const P3& p : c) rim &= on_rim(p, side), cap &= on_cap(p, side);
      if (rim) {
        ++along_rim;
        std::printf("    quad %d along the rim z = %g at (%.3f %.3f)\n", q, side * h, c[0][0], c[0][1]);
      }
      if (!cap) continue;
      ++on_caps;
      double nz = 0, len2 = 0;  // Newell's normal
      P3 n{0, 0, 0};
      for (int k = 0; k < 4; ++k) {
        const P3 &a = c[k], &b = c[(k + 1) % 4];
        n[0] += (a[1] - b[1]) * (a[2] + b[2]);
        n[1] += (a[2] - b[2]) * (a[0] + b[0]);
        n[2] += (a[0] - b[0]) * (a[1] + b[1]);
      }
      for (double x : n) len2 += x * x;
      nz = side * n[2];
      if (!(nz > 0.5 * std::sqrt(len2))) ++facing_away;
    }
  }
  EXPECT_GT(on_caps, 0);
  EXPECT_EQ(along_rim, 0) << "cage quads lying along a sharp rim (an ear's split)";
  EXPECT_EQ(facing_away, 0) << "cap quads facing more than 60 degrees away from their cap's normal";
}

// The coarse edge flips (regularize_valence) keep the topology and the features, and do not add
// irregular vertices: on the torus (Euler characteristic 0: a cage without extraordinary
// vertices exists) and on the drilled box (8 corners, 14 feature curves), with flips the cage has
// at most as many extraordinary vertices as without, and the flips ran.
TEST(QuadRemesh, ValenceFlipsKeepTopologyAndLowerIrregularity) {
  for (int shape = 0; shape < 2; ++shape) {
    MeshInput m = shape == 0 ? test::torus(2, 0.7, 90, 36) : test::drilled_box(0.4, 64, 8, 16);
    const auto [off, on] = off_and_on(m, {}, &QuadRemeshOptions::regularize_valence, 400);
    EXPECT_EQ(off.stats.flips, 0);
    EXPECT_GT(on.stats.flips, 0);
    EXPECT_LE(on.stats.extraordinary_vertices, off.stats.extraordinary_vertices) << "shape " << shape;
    EXPECT_EQ(on.cage.corners.size(), off.cage.corners.size());
    std::printf("  shape %d: %d flips, extraordinary vertices %d -> %d, unpaired triangles %d -> %d\n", shape,
                on.stats.flips, off.stats.extraordinary_vertices, on.stats.extraordinary_vertices,
                off.stats.coarse_triangles, on.stats.coarse_triangles);
  }
}

// The quad-dominant clean-up (cleanup, core/remesh/quad_cleanup.h) on the remesher's own coarse
// meshes: the torus (Euler characteristic 0: a cage without extraordinary vertices exists) gets
// strictly fewer extraordinary vertices than without it, the drilled box (8 corners, 14 feature
// curves, whose triangles sit beside the rims the pass may not make more irregular) no more; both
// keep their topology (check_cage), and the features are untouched: the same tagged edges (as
// pairs of end positions) and the same corners as without the pass.
TEST(QuadRemesh, CleanupLowersExtraordinaryVerticesAndKeepsFeatures) {
  using EdgeAt = std::pair<P3, P3>;
  auto tagged = [](const MeshInput& c) {
    std::set<EdgeAt> e;
    for (const auto& k : c.creases) e.insert(std::minmax(c.positions[k.v0], c.positions[k.v1]));
    return e;
  };
  auto corners = [](const MeshInput& c) {
    std::set<P3> v;
    for (const auto& k : c.corners) v.insert(c.positions[k.vertex]);
    return v;
  };
  for (int shape = 0; shape < 2; ++shape) {
    MeshInput m = shape == 0 ? test::torus(2, 0.7, 90, 36) : test::drilled_box(0.4, 64, 8, 16);
    const auto [off, on] = off_and_on(m, {}, &QuadRemeshOptions::cleanup, 400);
    EXPECT_EQ(off.stats.cleanup_rotations + off.stats.cleanup_merges, 0);
    EXPECT_GT(on.stats.cleanup_rotations + on.stats.cleanup_merges, 0);
    if (shape == 0)
      EXPECT_LT(on.stats.extraordinary_vertices, off.stats.extraordinary_vertices);
    else
      EXPECT_LE(on.stats.extraordinary_vertices, off.stats.extraordinary_vertices);
    EXPECT_EQ(tagged(on.cage), tagged(off.cage)) << "shape " << shape;
    EXPECT_EQ(corners(on.cage), corners(off.cage)) << "shape " << shape;
    // merges only remove interior coarse edges: each removes one coarse quad's worth of faces
    // (two triangles, 3 + 3 cage faces, become one quad, 4)
    EXPECT_EQ(on.stats.coarse_quads + on.stats.coarse_triangles,
              off.stats.coarse_quads + off.stats.coarse_triangles - on.stats.cleanup_merges);
    std::printf("  shape %d: %d rotations, %d merges, extraordinary vertices %d -> %d, unpaired triangles %d -> %d\n",
                shape, on.stats.cleanup_rotations, on.stats.cleanup_merges, off.stats.extraordinary_vertices,
                on.stats.extraordinary_vertices, off.stats.coarse_triangles, on.stats.coarse_triangles);
  }
}

// The size check aiming at the target (aim_at_target, docs/remesh.md step 7). Oracle: the request
// itself; the spec is the band 0.85 .. 1 x the target (no more faces than asked for, at most 15 %
// fewer: the size check aims at 0.9 .. 1 and keeps the nearest run when the lattice's noise, about
// +-8 % between nearby spacings, leaves the band unmet). Smooth closed shapes and a box (no
// feature floor): a sphere, a torus, a cube, each at two sizes. With the older check (one rerun
// only above 1.3 x) the sphere gives 312 quads for 300 and 824 for 800, the cube 864 for 800.
TEST(QuadRemesh, TargetCountIsMet) {
  struct Case {
    const char* name;
    MeshInput mesh;
    int target;
  };
  const std::vector<Case> cases = {{"sphere", test::icosphere(4), 300},  {"sphere", test::icosphere(4), 800},
                                   {"torus", test::torus(2, 0.7, 90, 36), 400}, {"torus", test::torus(2, 0.7, 90, 36), 1000},
                                   {"box", test::box(16), 400},          {"box", test::box(16), 800}};
  for (const Case& c : cases) {
    QuadRemeshOptions o;
    o.target_faces = c.target;
    o.aim_at_target = true;
    const QuadRemeshResult r = quad_remesh(c.mesh, o);
    std::printf("  %s target %d: %d quads (%.3f), %d runs\n", c.name, c.target, r.stats.faces,
                double(r.stats.faces) / c.target, r.stats.attempts);
    EXPECT_LE(r.stats.faces, c.target) << c.name;
    EXPECT_GE(r.stats.faces, 0.85 * c.target) << c.name;
    EXPECT_EQ(r.stats.faces, r.cage.num_faces());
  }
}

// The same cage bit for bit: positions, faces and crease tags.
void expect_same_cage(const MeshInput& a, const MeshInput& b) {
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.face_indices, b.face_indices);
  ASSERT_EQ(a.creases.size(), b.creases.size());
  for (size_t i = 0; i < a.creases.size(); ++i) {
    EXPECT_EQ(a.creases[i].v0, b.creases[i].v0);
    EXPECT_EQ(a.creases[i].v1, b.creases[i].v1);
  }
}

TEST(QuadRemesh, Deterministic) {
  MeshInput m = test::drilled_box(0.4, 32, 6, 8);
  QuadRemeshResult a = remesh(m, 250), b = remesh(m, 250);
  expect_same_cage(a.cage, b.cage);
}

// m with its vertices relabelled at random (as an STL's welded triangle soup numbers them), the
// surface the same.
MeshInput shuffled(const MeshInput& m, unsigned seed) {
  std::vector<int> label(m.positions.size());
  std::iota(label.begin(), label.end(), 0);
  std::shuffle(label.begin(), label.end(), std::mt19937(seed));
  MeshInput r = m;
  for (size_t v = 0; v < label.size(); ++v) r.positions[label[v]] = m.positions[v];
  for (int& i : r.face_indices) i = label[i];
  for (CreaseTag& c : r.creases) c.v0 = label[c.v0], c.v1 = label[c.v1];
  for (CornerTag& c : r.corners) c.vertex = label[c.vertex];
  return r;
}

// The fields' sweeps on two threads (core/util/wave_sweeps.h) give the one-thread cage bit for
// bit. The drilled box with its vertices numbered at random: the sweeps' waves are wide, so the
// dense mesh's sweeps do run on two threads where the machine has two.
TEST(QuadRemesh, ThreadsGiveTheSameCage) {
  const MeshInput m = shuffled(test::drilled_box(0.4, 32, 6, 8), 11);
  QuadRemeshResult one, two;
  {
    const ThreadLimit limit(1);
    one = remesh(m, 250);
  }
  {
    const ThreadLimit limit(2);
    two = remesh(m, 250);
  }
  check_cage(m, two, 250);
  EXPECT_EQ(one.stats.field_threads, 1);
  EXPECT_EQ(two.stats.field_threads, std::min(2, hardware_threads()));
  expect_same_cage(one.cage, two.cage);
}

TEST(QuadRemesh, EdgeLengthSetsTheSize) {
  // the sphere's area 4 pi over squares of side 0.2: ~314 quads
  MeshInput m = test::icosphere(4);
  QuadRemeshOptions o;
  o.edge_length = 0.2;
  QuadRemeshResult r = quad_remesh(m, o);
  check_cage(m, r, static_cast<int>(4 * test::kTestPi / 0.04));
}

// exact_spacing (docs/remesh.md step 7): one extraction at the spacing asked for. The drilled
// cube [-1, 1]^3 at edge length 0.5 has more faces than 1.3 x area / 0.25 (the hole's rims keep
// vertices of their own), so by default the extraction runs again at a coarser spacing. With
// exact_spacing it runs once, at the lattice spacing 2 x 0.5 (the request is the oracle), and
// the cube's twelve straight edges (length 2) are cut into segments of about the edge length:
// 24 / 0.5 = 48 cage edges along them within 20 % (by default 24: half as many).
TEST(QuadRemesh, ExactSpacingKeepsTheEdgeLength) {
  const double length = 0.5;
  const MeshInput m = test::drilled_box(0.2, 64, 6, 16);
  auto box_edges = [](const QuadRemeshResult& r) {  // crease edges on the cube's edges
    int n = 0;
    for (const auto& c : r.cage.creases) n += cube_planes_of_edge(r.cage.positions[c.v0], r.cage.positions[c.v1]) == 2;
    return n;
  };
  QuadRemeshOptions o;
  o.edge_length = length;
  const QuadRemeshResult loose = quad_remesh(m, o);
  o.exact_spacing = true;
  const QuadRemeshResult exact = quad_remesh(m, o);
  check_cage(m, exact, 0);  // manifold, oriented, its components (its count is far above 24 / 0.25: the point)
  std::printf("  edge length %g: by default %d runs, spacing %.4g, %d quads, %d edges along the cube's; exact: %d run, "
              "spacing %.4g, %d quads, %d edges\n", length, loose.stats.attempts, loose.stats.spacing,
              loose.cage.num_faces(), box_edges(loose), exact.stats.attempts, exact.stats.spacing, exact.cage.num_faces(),
              box_edges(exact));
  EXPECT_EQ(loose.stats.attempts, 2) << "no second run by default: the test cannot fail";
  EXPECT_EQ(exact.stats.attempts, 1);
  EXPECT_EQ(exact.stats.spacing, 2 * length);
  EXPECT_NEAR(box_edges(exact), 24 / length, 0.2 * 24 / length);
  EXPECT_LT(box_edges(loose), 0.8 * 24 / length);
}

TEST(QuadRemesh, SettingsAndCancel) {
  MeshInput m = test::icosphere(2);
  QuadRemeshOptions none;
  try {
    quad_remesh(m, none);
    FAIL() << "no size accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Settings);
  }
  QuadRemeshOptions both;
  both.target_faces = 10;
  both.edge_length = 0.1;
  EXPECT_THROW(quad_remesh(m, both), Error);
  QuadRemeshOptions ok;
  ok.target_faces = 100;
  int calls = 0;
  QuadRemeshResult r = quad_remesh(m, ok, [&](double f) {
    EXPECT_GE(f, 0.0);
    EXPECT_LE(f, 1.0);
    return ++calls < 3;
  });
  EXPECT_TRUE(r.cancelled);
  EXPECT_EQ(r.cage.num_faces(), 0);
}

// Real meshes of the test data: topology kept; the numbers go to the log.
// count_checked: the face count within 1.5x of the target (plate_holes: a thin plate with small holes
// gives more, see docs/remesh.md).
// A mesh of tests/data/mesh read as the mesh path reads it: its triangles as they are.
MeshInput read_test_mesh(const std::string& name) {
  MeshReadOptions triangles;
  triangles.recover_quads = false;
  return read_cage(std::string(SUBD2NURBS_TEST_DATA_DIR) + "/mesh/" + name, triangles).input;
}

void real_mesh(const std::string& name, int target, bool count_checked) {
  const MeshInput m = read_test_mesh(name);
  std::printf("%s: %d vertices, %d faces, target %d\n", name.c_str(), m.num_vertices(), m.num_faces(), target);
  QuadRemeshResult r = remesh(m, target);
  check_cage(m, r, count_checked ? target : 0);
  std::printf("  features: %zu edges, %zu corners, %d chains (%d dropped)\n", r.features.edges.size(),
              r.features.corners.size(), r.features.chains, r.features.dropped_short_chains);
}

TEST(QuadRemesh, Fandisk) { real_mesh("fandisk.off", 1000, true); }
TEST(QuadRemesh, PlateHoles) { real_mesh("plate_holes.STL", 200, false); }


// docs/remesh.md step 2: the cross field's singularities counted on the dense mesh obey
// Poincare-Hopf: on a closed surface their indices sum to its Euler characteristic, i.e. the
// quarter turns to 4 x chi (sphere and box 8, torus and the drilled box 0), whatever the field
// (smooth, or held along the box's sharp edges and the hole's rims).
TEST(QuadRemesh, FieldSingularitiesSumToEuler) {
  struct Case {
    const char* name;
    MeshInput mesh;
    int chi;
  };
  const std::vector<Case> cases = {{"sphere", test::icosphere(4), 2},
                                   {"torus", test::torus(3, 1, 96, 32), 0},
                                   {"box", test::box(12), 2},
                                   {"drilled box", test::drilled_box(0.4, 64, 6, 16), 0}};
  for (const Case& c : cases) {
    const QuadRemeshResult r = remesh(c.mesh, 400);
    std::printf("  %s: %d field singularities, index sum %d quarter turns, %d extraordinary vertices\n", c.name,
                r.stats.field_singularities, r.stats.field_index_sum, r.stats.extraordinary_vertices);
    EXPECT_EQ(r.stats.euler_input, c.chi) << c.name;
    EXPECT_EQ(r.stats.field_index_sum, 4 * c.chi) << c.name;
    EXPECT_GE(r.stats.field_singularities, std::abs(4 * c.chi)) << c.name;
  }
}

}  // namespace
// Stuck vertices (docs/remesh.md step 6c): a slab whose rounded corners (radius 0.06) are much
// tighter than the lattice spacing (~0.2 at 1000 quads), so the chain rule keeps extra rim
// vertices at the arcs and a wall vertex that could not collapse into the rim stays beside it.
// Oracle: the exact geometry. The caps are the planes z = +-h, so a wall vertex's distance from
// the rim is |z -+ h|: every cage quad along a rim crease on the wall side must have its two
// other vertices at least 0.4 x the crease edge's length from the rim (a square quad: 1). Without
// the move a quad 0.27 as high as long stays (a sliver across which the limit normal of the crease
// is ill-conditioned: fandisk's bottom rim); the move changes no count.
// The lowest wall quad along the rims of test::rounded_slab (caps at z = +-h): over the cage's
// quads with a crease edge on a cap's plane, the smallest height of its other two vertices above
// or below that plane, over the edge's length (measured from the exact planes).
static double lowest_wall_quad(const QuadRemeshResult& r, double h) {
  std::set<std::pair<int, int>> crease;
  for (const auto& c : r.cage.creases) crease.insert(std::minmax(c.v0, c.v1));
  double worst = INFINITY;
  for (int q = 0; q < r.cage.num_faces(); ++q) {
    const int* f = &r.cage.face_indices[4 * q];
    for (int k = 0; k < 4; ++k) {
      const P3 &a = r.cage.positions[f[k]], &b = r.cage.positions[f[(k + 1) % 4]];
      if (!crease.count(std::minmax(f[k], f[(k + 1) % 4])) || std::abs(std::abs(a[2]) - h) > 1e-9 ||
          std::abs(b[2] - a[2]) > 1e-9)
        continue;  // not a rim edge
      const double length = std::hypot(b[0] - a[0], b[1] - a[1]);
      for (int j : {f[(k + 2) % 4], f[(k + 3) % 4]}) {
        const double off = std::abs(r.cage.positions[j][2] - a[2]);
        if (off > 1e-9) worst = std::min(worst, off / length);  // a wall quad (not a cap's)
      }
    }
  }
  return worst;
}

TEST(QuadRemesh, NoSliverBesideATightRim) {
  const double rho = 0.06, h = 0.3;
  MeshInput m = test::rounded_slab(rho, h, 256, 16, 24);
  auto lowest_wall_quad = [&](const QuadRemeshResult& r) { return subd2nurbs::lowest_wall_quad(r, h); };
  QuadRemeshOptions o;
  o.pin_tight_arcs = false;  // the lattice of before step 3's arc pins: it leaves the stuck vertex
  const auto [off, on] = off_and_on(m, o, &QuadRemeshOptions::relocate_stuck, 1000);
  const double before = lowest_wall_quad(off), after = lowest_wall_quad(on);
  std::printf("  %d stuck vertices moved; lowest wall quad along a rim: %.3f -> %.3f of its length\n",
              on.stats.relocations, before, after);
  EXPECT_EQ(off.stats.relocations, 0);
  EXPECT_GT(on.stats.relocations, 0);
  EXPECT_LT(before, 0.4) << "the slab no longer has a stuck vertex: the test checks nothing";
  EXPECT_GE(after, 0.4);
  EXPECT_EQ(on.cage.num_faces(), off.cage.num_faces());
  EXPECT_EQ(on.stats.extraordinary_vertices, off.stats.extraordinary_vertices);
  EXPECT_EQ(on.cage.creases.size(), off.cage.creases.size());
}

// docs/remesh.md step 5, "Caps": plate_holes.STL's planes have coarse triangles with an angle
// above 160 degrees (a vertex almost on the opposite edge). Flipped, they pair into better quads:
// fewer extraordinary vertices. The flips change no lattice point (the size check counts the
// faces as they would be without them, so it never chooses another spacing for a second run):
// the coarse vertices, (V + chi) / 2 - coarse faces after the one split (V = V_c + E_c + F_c and
// V_c - E_c + F_c = chi), are the same number with the flips and without.
TEST(QuadRemesh, CapsFlipWithoutMovingTheLattice) {
  const MeshInput m = read_test_mesh("plate_holes.STL");
  // plate_holes gives more faces than the count check's 1.5x of 600 (real_mesh above)
  const auto [off, on] = off_and_on(m, {}, &QuadRemeshOptions::flip_caps, 600, false);
  auto coarse_vertices = [](const QuadRemeshResult& r) {
    return (r.cage.num_vertices() + r.stats.euler_cage) / 2 - (r.stats.coarse_quads + r.stats.coarse_triangles);
  };
  std::printf("  %d caps flipped; extraordinary vertices %d -> %d, quads %d -> %d\n", on.stats.cap_flips,
              off.stats.extraordinary_vertices, on.stats.extraordinary_vertices, off.cage.num_faces(), on.cage.num_faces());
  EXPECT_EQ(off.stats.cap_flips, 0);
  EXPECT_GT(on.stats.cap_flips, 0);
  EXPECT_EQ(on.stats.attempts, off.stats.attempts);
  EXPECT_EQ(coarse_vertices(on), coarse_vertices(off));
  EXPECT_LT(on.stats.extraordinary_vertices, off.stats.extraordinary_vertices);
  EXPECT_EQ(on.cage.creases.size(), off.cage.creases.size());
}

// Tight closed loops (docs/remesh.md step 4): a counterbored hole much narrower than the lattice
// (radii 0.15 and 0.3 against a spacing of ~0.5 .. 0.7) has four circular rims. The three with no
// room for a lattice row between them (the through hole's top rim, the floor's outer rim, the
// counterbore's top rim) are one group; the through hole's bottom rim, 1.6 below, is left to the
// lattice. Counted on the circles themselves (crease edges with both ends on the circle's radius
// and height), over two samplings and three sizes: left to the lattice, no size has the three
// rims with equal counts; aligned, most do (where one is left over, the last collapse along the
// rim was refused: the strip is narrower than the spacing), every rim keeps a polygon round its
// circle, and the strips between them (the counterbore's floor and wall) have fewer irregular
// vertices in sum.
TEST(QuadRemesh, TightLoopsLineUpTheRimsOfAHole) {
  const double r1 = 0.15, r2 = 0.3, c = 0.6;
  const std::array<std::array<double, 2>, 4> rims{{{r1, -1}, {r1, c}, {r2, c}, {r2, 1}}};
  auto on_rim = [&](const P3& p, int i) {  // (the dense chain's split points lie on chords: 1 %)
    return std::abs(std::hypot(p[0], p[1]) - rims[i][0]) < 0.01 * rims[i][0] && std::abs(p[2] - rims[i][1]) < 1e-9;
  };
  struct Counts {
    std::array<int, 4> rim_edges{};
    int strip_irregular = 0;
  };
  auto counts = [&](const QuadRemeshResult& r) {
    Counts k;
    for (const auto& e : r.cage.creases)
      for (int i = 0; i < 4; ++i)
        if (on_rim(r.cage.positions[e.v0], i) && on_rim(r.cage.positions[e.v1], i)) ++k.rim_edges[i];
    std::vector<int> valence(r.cage.num_vertices(), 0);  // closed: a vertex's faces = its edges
    for (int f = 0; f < r.cage.num_faces(); ++f)
      for (int j = 0; j < 4; ++j) ++valence[r.cage.face_indices[4 * f + j]];
    for (int v = 0; v < r.cage.num_vertices(); ++v) {
      const P3& p = r.cage.positions[v];
      const double rho = std::hypot(p[0], p[1]);
      const bool floor = std::abs(p[2] - c) < 1e-6 && rho > r1 + 1e-6 && rho < r2 - 1e-6;
      const bool wall = std::abs(rho - r2) < 0.05 && p[2] > c + 1e-6 && p[2] < 1 - 1e-6;
      k.strip_irregular += (floor || wall) && valence[v] != 4;
    }
    return k;
  };
  int irregular_off = 0, irregular_on = 0, equal_off = 0, equal_on = 0;
  for (int m : {48, 64}) {
    const MeshInput mesh = test::counterbored_box(r1, r2, c, m, 6, 8);
    for (int target : {200, 300, 400}) {
      QuadRemeshOptions o;
      o.target_faces = target;
      o.align_tight_loops = false;
      const QuadRemeshResult off = quad_remesh(mesh, o);
      o.align_tight_loops = true;
      const QuadRemeshResult on = quad_remesh(mesh, o);
      check_cage(mesh, off, target);
      check_cage(mesh, on, target);
      const Counts a = counts(off), b = counts(on);
      std::printf("  %d samples, %d quads: rim edges off %d %d %d %d, on %d %d %d %d; irregular strip vertices %d -> %d\n",
                  m, target, a.rim_edges[0], a.rim_edges[1], a.rim_edges[2], a.rim_edges[3], b.rim_edges[0],
                  b.rim_edges[1], b.rim_edges[2], b.rim_edges[3], a.strip_irregular, b.strip_irregular);
      EXPECT_EQ(off.stats.tight_loops, 0);
      EXPECT_EQ(on.stats.tight_loops, 3);
      EXPECT_GE(b.rim_edges[1], 6);  // a polygon round the circle, not a chord
      EXPECT_GE(b.rim_edges[2], 6);
      EXPECT_GE(b.rim_edges[3], 6);
      equal_off += a.rim_edges[1] == a.rim_edges[2] && a.rim_edges[2] == a.rim_edges[3];
      equal_on += b.rim_edges[1] == b.rim_edges[2] && b.rim_edges[2] == b.rim_edges[3];
      irregular_off += a.strip_irregular;
      irregular_on += b.strip_irregular;
    }
  }
  std::printf("  sizes with the three rims equal: %d -> %d of 6; irregular strip vertices %d -> %d\n", equal_off,
              equal_on, irregular_off, irregular_on);
  EXPECT_GE(equal_on, 4);
  EXPECT_GT(equal_on, equal_off);
  EXPECT_LT(irregular_on, irregular_off);
}

// docs/remesh.md step 3: the position field pins a lattice column at each tight arc of a feature
// chain, so the side under a rim that rounds a corner of the part (radius 0.06, a fifth of the
// lattice spacing 0.3 at 1000 quads) has a row under each kept rim vertex and no vertex stays
// stuck beside the crease. Without the pins the lowest wall quad along a rim is a sliver (its
// height a quarter of its length, docs/remesh.md step 6c); with them it is at least 0.4 of its
// length without moving any vertex afterwards (relocate_stuck off).
TEST(QuadRemesh, TightArcPinsALatticeColumn) {
  const double rho = 0.06, h = 0.3;
  MeshInput m = test::rounded_slab(rho, h, 256, 16, 24);
  QuadRemeshOptions o;
  o.relocate_stuck = false;
  const auto [off, on] = off_and_on(m, o, &QuadRemeshOptions::pin_tight_arcs, 1000);
  const double before = lowest_wall_quad(off, h), after = lowest_wall_quad(on, h);
  std::printf("  %d arc pins; lowest wall quad along a rim: %.3f -> %.3f of its length; faces %d -> %d, "
              "extraordinary %d -> %d\n",
              on.stats.arc_pins, before, after, off.cage.num_faces(), on.cage.num_faces(),
              off.stats.extraordinary_vertices, on.stats.extraordinary_vertices);
  EXPECT_EQ(off.stats.arc_pins, 0);
  EXPECT_GT(on.stats.arc_pins, 0);
  EXPECT_LT(before, 0.4) << "the slab no longer has a stuck vertex without the pins: the test checks nothing";
  EXPECT_GE(after, 0.4);
  EXPECT_LE(on.stats.extraordinary_vertices, off.stats.extraordinary_vertices);
}


// docs/remesh.md step 3b: a uniform lattice cannot close round a torus (its parallels are 2.9
// times longer outside than inside, R + r against R - r), so the position field has
// dislocations even though its cross field has no singularity; each became a pair of
// extraordinary vertices. Cancelled in pairs, the lattice stretches instead: fewer
// extraordinary vertices, and the cage's edges follow the torus's principal directions (the
// parallels and the meridians, known exactly) more closely. Both with the same field and size.
TEST(QuadRemesh, DislocationsCancelInPairsOnATorus) {
  const double major = 2, minor = 0.7;
  const MeshInput m = test::torus(major, minor, 90, 36);
  // The mean angle (degrees) between the cage's edges and the nearer principal direction at
  // their midpoints (the tangent of the parallel there, or the meridian's, 90 degrees from it).
  auto misalignment = [&](const MeshInput& c) {
    double sum = 0;
    int count = 0;
    size_t o = 0;
    for (int size : c.face_sizes) {
      for (int k = 0; k < size; ++k) {
        const P3 a = c.positions[c.face_indices[o + k]], b = c.positions[c.face_indices[o + (k + 1) % size]];
        const Eigen::Vector3d pa(a[0], a[1], a[2]), pb(b[0], b[1], b[2]);
        const Eigen::Vector3d mid = 0.5 * (pa + pb);
        const Eigen::Vector3d axis_point = Eigen::Vector3d(mid.x(), mid.y(), 0).normalized() * major;
        const Eigen::Vector3d n = (mid - axis_point).normalized();
        const Eigen::Vector3d parallel = Eigen::Vector3d(-mid.y(), mid.x(), 0).normalized();
        Eigen::Vector3d e = pb - pa;
        e -= n * n.dot(e);
        const double angle = std::acos(std::min(1.0, std::abs(e.normalized().dot(parallel)))) * 180 / test::kTestPi;
        sum += std::min(angle, 90 - angle);
        ++count;
      }
      o += static_cast<size_t>(size);
    }
    return sum / count;
  };
  // Summed over three sizes and two tori (one size alone is noisy: the singularity-free field
  // leaves the lattice free to slide, and which rows end where changes with the size).
  int ev_off = 0, ev_on = 0, before = 0, left = 0;
  double mis_off = 0, mis_on = 0;
  for (const int target : {300, 600, 1000})
    for (int shape = 0; shape < 2; ++shape) {
      const MeshInput mesh = shape == 0 ? m : test::torus(3, 1, 96, 32);
      const auto [off, on] = off_and_on(mesh, {}, &QuadRemeshOptions::cancel_dislocations, target);
      EXPECT_EQ(on.stats.field_singularities, 0);
      EXPECT_EQ(off.stats.position_dislocations, 0);  // not counted when off
      ev_off += off.stats.extraordinary_vertices;
      ev_on += on.stats.extraordinary_vertices;
      before += on.stats.position_dislocations;
      left += on.stats.position_dislocations_left;
      if (shape == 0) mis_off += misalignment(off.cage) / 3, mis_on += misalignment(on.cage) / 3;
    }
  EXPECT_GT(before, 6 * 8);
  EXPECT_LE(4 * left, before);
  EXPECT_LT(ev_on, 0.85 * ev_off);
  EXPECT_LT(mis_on, mis_off - 1.0);
  std::printf("  dislocated triangles %d -> %d; extraordinary vertices %d -> %d; edges off the principal directions "
              "%.1f -> %.1f degrees (mean)\n", before, left, ev_off, ev_on, mis_off, mis_on);
}

}  // namespace subd2nurbs
