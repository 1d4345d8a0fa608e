// Planar regions (core/fit/planar_regions): detected on analytic meshes (a box, a rotated box, a
// box with a drilled hole) against their analytic planes; the limit support of a cage face
// checked by perturbing every other vertex (the face's limit must not move); and the flattening
// of a remeshed, perturbed cage checked against the analytic planes: exactly the faces whose
// whole support lies on one of the box's planes are flattened, and their limit surface lies in
// that plane to rounding.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/fit/planar_regions.h"
#include "core/limit/limit_evaluator.h"
#include "core/refine/refiner.h"
#include "core/remesh/quad_remesh.h"
#include "remesh/test_meshes.h"

namespace subd2nurbs {
namespace {

std::vector<std::array<int, 3>> triangles_of(const MeshInput& m) {
  std::vector<std::array<int, 3>> t;
  for (int f = 0; f < m.num_faces(); ++f) t.push_back({m.face_indices[3 * f], m.face_indices[3 * f + 1], m.face_indices[3 * f + 2]});
  return t;
}

/// A deterministic displacement of size about `amplitude` for vertex v.
Point3 wobble(int v, double amplitude) {
  return {amplitude * std::sin(1.3 * v + 0.2), amplitude * std::cos(2.1 * v + 0.7), amplitude * std::sin(0.7 * v + 1.9)};
}

TEST(PlanarRegions, BoxHasSixAxisPlanes) {
  const MeshInput box = test::box(8);
  const auto regions = detect_planar_regions(box.positions, triangles_of(box));
  ASSERT_EQ(regions.size(), 6u);
  for (const PlanarRegion& r : regions) {
    EXPECT_EQ(r.triangles.size(), 2u * 8 * 8);
    EXPECT_NEAR(r.area, 4.0, 1e-12);
    // one axis, outward: the plane x_a = +-1
    int axis = 0;
    for (int k = 1; k < 3; ++k)
      if (std::abs(r.normal[k]) > std::abs(r.normal[axis])) axis = k;
    EXPECT_NEAR(std::abs(r.normal[axis]), 1.0, 1e-14);
    const double side = r.normal[axis] > 0 ? 1 : -1;
    EXPECT_NEAR(r.point[axis], side, 1e-14);
    EXPECT_LT(r.deviation, 1e-15);
  }
}

TEST(PlanarRegions, RotatedBoxPlanesAreTheRotatedAxes) {
  MeshInput box = test::box(6);
  // rotation by 0.3 about z then 0.5 about x
  const double c1 = std::cos(0.3), s1 = std::sin(0.3), c2 = std::cos(0.5), s2 = std::sin(0.5);
  auto rotate = [&](const Point3& p) {
    const Point3 q{c1 * p[0] - s1 * p[1], s1 * p[0] + c1 * p[1], p[2]};
    return Point3{q[0], c2 * q[1] - s2 * q[2], s2 * q[1] + c2 * q[2]};
  };
  for (Point3& p : box.positions) p = rotate(p);
  const auto regions = detect_planar_regions(box.positions, triangles_of(box));
  ASSERT_EQ(regions.size(), 6u);
  for (const PlanarRegion& r : regions) {
    // the normal is one of the rotated axes, and the plane is at distance 1 from the centre
    double best = 0;
    for (int a = 0; a < 3; ++a) {
      Point3 e{0, 0, 0};
      e[a] = 1;
      const Point3 n = rotate(e);
      best = std::max(best, std::abs(n[0] * r.normal[0] + n[1] * r.normal[1] + n[2] * r.normal[2]));
    }
    EXPECT_NEAR(best, 1.0, 1e-13);
    EXPECT_NEAR(r.point[0] * r.normal[0] + r.point[1] * r.normal[1] + r.point[2] * r.normal[2], 1.0, 1e-13);
  }
}

TEST(PlanarRegions, DrilledBoxFacetsAreNarrow) {
  // 32 facets of the hole's wall are planar strips 2 pi 0.4 / 32 = 0.079 wide: regions of their
  // own unless narrower than min_width.
  const MeshInput m = test::drilled_box(0.4, 32, 4, 8);
  EXPECT_EQ(detect_planar_regions(m.positions, triangles_of(m)).size(), 6u + 32u);
  PlanarRegionOptions o;
  o.min_width = 0.2;
  const auto regions = detect_planar_regions(m.positions, triangles_of(m), o);
  ASSERT_EQ(regions.size(), 6u);
  const double hole_area = 3.14159265358979 * 0.4 * 0.4;
  int caps = 0;
  for (const PlanarRegion& r : regions)
    if (std::abs(r.normal[2]) > 0.5) {
      ++caps;
      EXPECT_NEAR(r.area, 4.0 - hole_area, 0.01);  // the hole a 32-gon
    }
  EXPECT_EQ(caps, 2);
}

QuadRemeshResult remeshed(const MeshInput& m, int faces) {
  QuadRemeshOptions o;
  o.target_faces = faces;
  return quad_remesh(m, o);
}

TEST(PlanarRegions, LimitSupportHoldsEveryInfluence) {
  // The drilled box's cage: crease curves along the box's edges and the hole's rims, corners.
  const QuadRemeshResult rr = remeshed(test::drilled_box(0.4, 32, 4, 8), 200);
  const SubdivLevel cage = SubdivLevel::from_input(rr.cage);
  const std::vector<Point3>& p = rr.cage.positions;
  const LimitEvaluator limit(cage, p);
  const int nv = cage.mesh.num_vertices();
  int checked = 0, smaller = 0;
  for (int f = 0; f < cage.mesh.num_faces(); f += 3) {
    const std::vector<int> support = limit_support(cage, f);
    std::vector<Point3> moved = p;
    for (int v = 0; v < nv; ++v)
      if (!std::binary_search(support.begin(), support.end(), v)) moved[v] = {p[v][0] + wobble(v, 0.3)[0], p[v][1] + wobble(v, 0.3)[1], p[v][2] + wobble(v, 0.3)[2]};
    const LimitEvaluator other(cage, moved);
    for (double u : {0.0, 0.3, 1.0})
      for (double w : {0.0, 0.6, 1.0}) {
        const Point3 a = limit.evaluate_point(f, 0, u, w).p, b = other.evaluate_point(f, 0, u, w).p;
        for (int k = 0; k < 3; ++k) ASSERT_NEAR(a[k], b[k], 1e-13) << "face " << f << " at " << u << ", " << w;
      }
    ++checked;
    // a face next to a crease curve has a smaller support than its whole 1-ring of faces
    std::vector<int> ring;
    for (int h = cage.mesh.face_begin(f); h < cage.mesh.face_end(f); ++h) {
      const int v = cage.mesh.corner_vertex(h);
      for (int i = 0; i < cage.mesh.vertex_face_count(v); ++i) {
        const int g = cage.mesh.corner_face(cage.mesh.vertex_corners(v)[i]);
        for (int hh = cage.mesh.face_begin(g); hh < cage.mesh.face_end(g); ++hh) ring.push_back(cage.mesh.corner_vertex(hh));
      }
    }
    std::sort(ring.begin(), ring.end());
    ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
    if (support.size() < ring.size()) ++smaller;
  }
  EXPECT_GT(checked, 50);
  EXPECT_GT(smaller, 10);  // the creases do cut supports
}

/// Distance of p to the surface of the box [-1, 1]^3 with a hole of radius r along z.
double box_distance(const Point3& p) {
  double inside = INFINITY, outside = 0;
  for (int k = 0; k < 3; ++k) {
    const double d = std::abs(p[k]) - 1;
    inside = std::min(inside, -d);
    outside += d > 0 ? d * d : 0;
  }
  return outside > 0 ? std::sqrt(outside) : inside;
}

/// The drilled box's cage, its vertices displaced (as a fit leaves them), flattened; every
/// flattened face must be one whose whole support lies on a plane of the box (the analytic
/// rule, computed here from the exact planes), every such face flattened, and its limit in
/// the plane to rounding.
void check_flattened(const MeshInput& mesh, int faces, double min_width, double min_fraction) {
  const QuadRemeshResult rr = remeshed(mesh, faces);
  const SubdivLevel cage = SubdivLevel::from_input(rr.cage);
  const std::vector<Point3>& on_mesh = rr.cage.positions;
  const int nv = cage.mesh.num_vertices(), nf = cage.mesh.num_faces();
  std::vector<Point3> fitted = on_mesh;
  for (int v = 0; v < nv; ++v)
    for (int k = 0; k < 3; ++k) fitted[v][k] += wobble(v, 3e-3)[k];
  std::vector<Point3> positions = fitted;
  PlanarRegionOptions po;
  po.min_width = min_width;
  const auto regions = detect_planar_regions(mesh.positions, triangles_of(mesh), po);
  const double diag = std::sqrt(12.0);
  const FlattenStats s =
      flatten_planar_regions(cage, on_mesh, positions, mesh.positions, triangles_of(mesh), regions, diag);
  // The analytic rule: the plane x_axis = side holds the face's support (on the mesh).
  int expected = 0;
  std::vector<char> moved_ok(nv, 0);
  const LimitEvaluator limit(cage, positions);
  double worst = 0;
  for (int f = 0; f < nf; ++f) {
    const std::vector<int> support = limit_support(cage, f);
    int plane = -1;
    for (int a = 0; a < 3 && plane < 0; ++a)
      for (int side = -1; side <= 1 && plane < 0; side += 2)
        if (std::all_of(support.begin(), support.end(), [&](int v) { return std::abs(on_mesh[v][a] - side) < 1e-12; }))
          plane = 2 * a + (side > 0);
    if (plane >= 0) ++expected;
    ASSERT_EQ(s.face_region[f] >= 0, plane >= 0) << "face " << f;
    if (plane < 0) continue;
    const int a = plane / 2;
    const double side = plane % 2 ? 1.0 : -1.0;
    EXPECT_NEAR(std::abs(regions[s.face_region[f]].normal[a]), 1.0, 1e-14);
    for (int v : support) moved_ok[v] = 1;
    for (int i = 0; i <= 4; ++i)
      for (int j = 0; j <= 4; ++j) {
        const Point3 p = limit.evaluate_point(f, 0, i / 4.0, j / 4.0).p;
        worst = std::max(worst, std::abs(p[a] - side));
        EXPECT_LT(box_distance(p), 1e-6 * diag);  // on the box, not only on the plane
      }
  }
  EXPECT_LT(worst, 1e-14 * diag);
  EXPECT_EQ(s.faces, expected);
  EXPECT_GE(expected, min_fraction * nf) << expected << " of " << nf;
  // Only support vertices of flattened faces move.
  for (int v = 0; v < nv; ++v) {
    if (!moved_ok[v]) {
      EXPECT_EQ(positions[v], fitted[v]) << "vertex " << v;
    }
  }
  std::printf("  %d of %d faces flattened (%d regions), limit within %.2g of the planes (fitted: %.2g), max move %.2g\n",
              s.faces, nf, s.regions_used, worst / diag, s.flatness_before, s.max_move);
  EXPECT_GT(s.flatness_before, 1e-4);  // the displacement did leave the faces off their planes
}

TEST(PlanarRegions, BoxCageFlattenedOntoItsPlanes) { check_flattened(test::box(16), 300, 0, 0.99); }

TEST(PlanarRegions, DrilledBoxCageFlattenedOntoItsPlanes) {
  check_flattened(test::drilled_box(0.4, 32, 4, 8), 300, 0.2, 0.4);
}

/// The mesh path's setting: regions of any width (docs/fitting.md "Planar regions"). The hole's
/// 32 facet strips (0.08 wide, a cage edge ~0.3) are regions now, yet none holds a face: a face
/// is flattened exactly when its support lies on a box plane, as with the width limit.
TEST(PlanarRegions, DrilledBoxNarrowFacetsHoldNoFace) {
  check_flattened(test::drilled_box(0.4, 32, 4, 8), 300, 0, 0.4);
}


/// The fit moves a held vertex freely along its plane and can fold the quads there (plate_holes'
/// top and bottom, issue #28): the folded faces' limit turns over, and the region's planar face is
/// refused. One free vertex of the drilled box's top (z = 1: smooth, in the support of top faces
/// only, by the analytic rule) is thrown past a neighbour, inverting faces. After the flattening
/// every flattened face of the top must be a strictly convex quad in the plane and its limit
/// must face +z (du x dv . z > 0 at 5 x 5 samples) and lie in z = 1: the analytic plane and its
/// orientation are the oracle.
TEST(PlanarRegions, FoldedFreeVertexUntangledInItsPlane) {
  const MeshInput mesh = test::drilled_box(0.4, 32, 4, 8);
  const QuadRemeshResult rr = remeshed(mesh, 300);
  const SubdivLevel cage = SubdivLevel::from_input(rr.cage);
  const PolyMesh& m = cage.mesh;
  const std::vector<Point3>& on_mesh = rr.cage.positions;
  const int nv = m.num_vertices(), nf = m.num_faces();
  auto on_top = [&](const std::vector<int>& vs) {
    return std::all_of(vs.begin(), vs.end(), [&](int v) { return std::abs(on_mesh[v][2] - 1) < 1e-12; });
  };
  std::vector<char> only_top(nv, 1);
  for (int f = 0; f < nf; ++f) {
    const std::vector<int> sup = limit_support(cage, f);
    if (!on_top(sup))
      for (int v : sup) only_top[v] = 0;
  }
  int moved = -1;
  for (int v = 0; v < nv && moved < 0; ++v)
    if (only_top[v] && std::abs(on_mesh[v][2] - 1) < 1e-12 && vertex_rule(cage, v) == VertexRule::Smooth &&
        !m.is_boundary_vertex(v))
      moved = v;
  ASSERT_GE(moved, 0);
  std::vector<Point3> positions = on_mesh;
  int neighbour = -1;
  for_each_vertex_edge(m, moved, [&](int, int u) { if (neighbour < 0) neighbour = u; });
  for (int k = 0; k < 2; ++k) positions[moved][k] += 2.5 * (on_mesh[neighbour][k] - on_mesh[moved][k]);
  const auto regions = detect_planar_regions(mesh.positions, triangles_of(mesh));
  const double diag = std::sqrt(12.0);
  const FlattenStats s =
      flatten_planar_regions(cage, on_mesh, positions, mesh.positions, triangles_of(mesh), regions, diag);
  EXPECT_GT(s.faces_folded_before, 0);
  EXPECT_EQ(s.faces_folded_after, 0);
  const LimitEvaluator limit(cage, positions);
  int top_faces = 0;
  for (int f = 0; f < nf; ++f) {
    if (s.face_region[f] < 0 || !on_top(limit_support(cage, f))) continue;
    ++top_faces;
    const int b = m.face_begin(f), n = m.face_size(f);
    for (int i = 0; i < n; ++i) {
      const Point3& p = positions[m.corner_vertex(b + (i + n - 1) % n)];
      const Point3& q = positions[m.corner_vertex(b + i)];
      const Point3& r = positions[m.corner_vertex(b + (i + 1) % n)];
      EXPECT_GT((q[0] - p[0]) * (r[1] - q[1]) - (q[1] - p[1]) * (r[0] - q[0]), 0) << "face " << f << " corner " << i;
    }
    for (int i = 0; i <= 4; ++i)
      for (int j = 0; j <= 4; ++j) {
        const LimitPoint lp = limit.evaluate_point(f, 0, 0.1 + 0.2 * i, 0.1 + 0.2 * j);
        EXPECT_NEAR(lp.p[2], 1.0, 1e-14);
        EXPECT_GT(lp.du[0] * lp.dv[1] - lp.du[1] * lp.dv[0], 0) << "face " << f;
      }
  }
  EXPECT_GT(top_faces, 10);
  std::printf("  %d top faces; %d faces not convex after the fold, %d after; %d free vertices, %d laid out again\n",
              top_faces, s.faces_folded_before, s.faces_folded_after, s.vertices_free, s.vertices_untangled);
}

}  // namespace
}  // namespace subd2nurbs
