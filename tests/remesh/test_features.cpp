// detect_features on analytic meshes: a box's 12 edges and 8 corners, none on a sphere, the
// boundary loops of an open cylinder, a short ridge dropped as noise, user-tagged creases kept.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <utility>

#include "core/features/features.h"
#include "core/remesh/quad_remesh.h"
#include "core/util/error.h"
#include "remesh/test_meshes.h"

namespace subd2nurbs {
namespace {

using test::P3;

bool on_box_edge(const P3& p) {
  int fixed = 0;
  for (double c : p) fixed += std::abs(std::abs(c) - 1) < 1e-12;
  return fixed >= 2;
}

TEST(Features, BoxHasItsTwelveEdgesAndEightCorners) {
  const int n = 8;
  MeshInput mesh = test::box(n);
  FeatureSet fs = detect_features(mesh);
  // the analytic sharp edges: mesh edges with both ends on the same box edge
  int expected = 0;
  std::vector<std::array<int, 2>> edges;
  int begin = 0;
  for (int f = 0; f < mesh.num_faces(); ++f, begin += 3)
    for (int k = 0; k < 3; ++k) {
      int a = mesh.face_indices[begin + k], b = mesh.face_indices[begin + (k + 1) % 3];
      if (a > b) continue;  // each edge of the closed mesh once
      const P3 &pa = mesh.positions[a], &pb = mesh.positions[b];
      int same = 0;
      for (int c = 0; c < 3; ++c) same += std::abs(std::abs(pa[c]) - 1) < 1e-12 && pa[c] == pb[c];
      if (same >= 2) ++expected;
    }
  EXPECT_EQ(expected, 12 * n);
  EXPECT_EQ(static_cast<int>(fs.edges.size()), expected);
  for (const auto& e : fs.edges) {
    EXPECT_LT(e[0], e[1]);
    EXPECT_TRUE(on_box_edge(mesh.positions[e[0]]) && on_box_edge(mesh.positions[e[1]]));
  }
  EXPECT_TRUE(std::is_sorted(fs.edges.begin(), fs.edges.end()));
  ASSERT_EQ(fs.corners.size(), 8u);
  for (int c : fs.corners) {
    for (double x : mesh.positions[c]) EXPECT_EQ(std::abs(x), 1.0);
  }
  EXPECT_EQ(fs.chains, 12);
  EXPECT_EQ(fs.dropped_short_chains, 0);
}

TEST(Features, SphereHasNone) {
  FeatureSet fs = detect_features(test::icosphere(3));
  EXPECT_TRUE(fs.edges.empty());
  EXPECT_TRUE(fs.corners.empty());
  EXPECT_EQ(fs.chains, 0);
}

TEST(Features, OpenCylinderHasItsTwoBoundaryLoops) {
  const int nu = 32;
  FeatureSet fs = detect_features(test::open_cylinder(1, 2, nu, 6));
  EXPECT_EQ(static_cast<int>(fs.edges.size()), 2 * nu);
  EXPECT_TRUE(fs.corners.empty());  // the loops turn by 360/32 degrees per vertex
  EXPECT_EQ(fs.chains, 2);
}

// A square grid with a tent-shaped ridge along x = 0 whose height fades away from y = 0: the ridge
// edges bend by 2 atan(0.364 (1 - |y| / 3)) (40 degrees at y = 0, below 30 beyond |y| ~ 0.79),
// every other edge by less than 17 degrees. Boundary: 4 chains between 4 corners.
MeshInput ridge_grid() {
  test::MeshBuilder b;
  b.patch([](double u, double v) {
    double x = 2 * u - 1, y = 2 * v - 1;
    return P3{x, y, 0.4367 * (1 - std::abs(x) / 1.2) * (1 - std::abs(y) / 3)};
  }, 10, 10);
  return b.mesh();
}

TEST(Features, ShortIsolatedChainIsDroppedUnlessLongEnoughOrTagged) {
  MeshInput mesh = ridge_grid();
  auto is_ridge = [&](const std::array<int, 2>& e) {
    const P3 &a = mesh.positions[e[0]], &b = mesh.positions[e[1]];
    return a[0] == 0 && b[0] == 0 && std::abs(a[1]) < 0.99 && std::abs(b[1]) < 0.99;
  };
  auto ridge_edges = [&](const FeatureSet& fs) {
    return static_cast<int>(std::count_if(fs.edges.begin(), fs.edges.end(), is_ridge));
  };
  FeatureOptions all;
  all.min_chain_edges = 1;
  all.fade_angle_degrees = 0;  // the ridge fades below 30 degrees towards the boundary: the next test
  FeatureSet kept = detect_features(mesh, all);
  int ridge = ridge_edges(kept);
  EXPECT_EQ(ridge, 8);  // |y| <= 0.8: the edges whose bend exceeds 30 degrees
  EXPECT_EQ(static_cast<int>(kept.edges.size()), 40 + ridge);  // nothing else but the boundary
  EXPECT_EQ(kept.corners.size(), 6u);  // the boundary's 4 and the ridge's two ends
  EXPECT_EQ(kept.chains, 5);
  EXPECT_EQ(kept.dropped_short_chains, 0);

  FeatureOptions longer;
  longer.min_chain_edges = ridge + 1;
  longer.fade_angle_degrees = 0;
  FeatureSet dropped = detect_features(mesh, longer);
  EXPECT_EQ(ridge_edges(dropped), 0);
  EXPECT_EQ(dropped.dropped_short_chains, 1);
  EXPECT_EQ(dropped.edges.size(), 40u);  // the boundary (longer than the minimum too, but kept)
  EXPECT_EQ(dropped.corners.size(), 4u);
  EXPECT_EQ(dropped.chains, 4);

  // the same edges tagged by the user are kept whatever their length
  MeshInput tagged = mesh;
  for (const auto& e : kept.edges)
    if (is_ridge(e)) tagged.creases.push_back({e[0], e[1], kInfiniteSharpness});
  FeatureSet user = detect_features(tagged, longer);
  EXPECT_EQ(ridge_edges(user), ridge);
  EXPECT_EQ(user.dropped_short_chains, 0);
}

// Fading creases: the ridge above bends by less than 30 degrees (27) on its last edges before
// the boundary, less on each edge than on the one before it, more than every edge beside it: by
// default its chain is continued there and joins the boundary (two junctions: corners).
TEST(Features, FadingRidgeIsContinuedIntoTheBoundary) {
  MeshInput mesh = ridge_grid();
  FeatureSet fs = detect_features(mesh);
  const int on_line = static_cast<int>(std::count_if(fs.edges.begin(), fs.edges.end(), [&](const std::array<int, 2>& e) {
    return mesh.positions[e[0]][0] == 0 && mesh.positions[e[1]][0] == 0;
  }));
  EXPECT_EQ(on_line, 10);  // the whole line x = 0, y in [-1, 1]
  EXPECT_EQ(fs.faded_edges, 2);
  EXPECT_TRUE(fs.darts.empty());
  EXPECT_EQ(fs.corners.size(), 6u);  // the boundary's 4 and the two junctions
  EXPECT_EQ(fs.chains, 7);           // the ridge, and the boundary's two sides split in two
}

// A tent along x = 0 whose height fades smoothly to nothing at y = 1.5 (smoothstep): its ridge
// bends by 2 atan(k(y)), 53 degrees for y <= 0, 30 at k = tan 15 deg, 0 from y = 1.5 on. Its chain
// is continued through the edges below 30 degrees as long as they fade, and ends in a dart, on
// the line, between where the bend is 30 degrees and where it is 0; nothing else is a feature.
TEST(Features, FadingCreaseEndsInADart) {
  auto k = [](double y) {
    const double t = std::clamp(y / 1.5, 0.0, 1.0);
    return 0.5 * (1 - t * t * (3 - 2 * t));
  };
  test::MeshBuilder b;
  b.patch([&](double u, double v) {
    const double x = 2 * u - 1, y = 3 * v - 1;
    return P3{x, y, k(y) * (1.2 - std::abs(x))};
  }, 20, 30);
  MeshInput mesh = b.mesh();
  auto bend_at = [&](double y) { return 2 * std::atan(k(y)) * 180 / 3.14159265358979323846; };  // each side's slope is k
  double y_30 = 0;
  while (bend_at(y_30) > 30) y_30 += 1e-4;
  FeatureSet fs = detect_features(mesh);
  double y_min = INFINITY, y_max = -INFINITY;
  int interior = 0;
  for (const auto& e : fs.edges) {
    const P3 &a = mesh.positions[e[0]], &c = mesh.positions[e[1]];
    const bool boundary_edge = (std::abs(a[0]) == 1 && a[0] == c[0]) || (std::abs(a[1] - 0.5) == 1.5 && a[1] == c[1]);
    if (boundary_edge) continue;
    ++interior;
    EXPECT_EQ(a[0], 0.0);  // only the ridge
    EXPECT_EQ(c[0], 0.0);
    y_min = std::min({y_min, a[1], c[1]}), y_max = std::max({y_max, a[1], c[1]});
  }
  EXPECT_EQ(y_min, -1.0);  // from the boundary (a junction there)
  ASSERT_EQ(fs.darts.size(), 1u);
  const P3& dart = mesh.positions[fs.darts[0]];
  EXPECT_EQ(dart[0], 0.0);
  EXPECT_EQ(dart[1], y_max);
  EXPECT_GT(y_max, y_30 + 0.1);  // continued beyond the feature angle...
  EXPECT_LE(y_max, 1.5);         // ... not beyond the tent
  EXPECT_GE(fs.faded_edges, 2);
  EXPECT_TRUE(std::binary_search(fs.corners.begin(), fs.corners.end(), fs.darts[0]));  // held like a corner by the remesher

  FeatureOptions off;
  off.fade_angle_degrees = 0;
  FeatureSet plain = detect_features(mesh, off);
  EXPECT_TRUE(plain.darts.empty());
  EXPECT_EQ(plain.faded_edges, 0);
  EXPECT_EQ(plain.edges.size() + static_cast<std::size_t>(fs.faded_edges), fs.edges.size());
  EXPECT_GT(interior, 0);
}

// Plane edges: a floor (x in [-10, 0], z = 0) and a wall (x = 1, z in [1, 10]) joined by a
// fillet of radius 1 in 6 facets of 15 degrees, extruded along y. Its first and last facet
// edges, the fillet's tangent lines, bend by 7.5 degrees (half a facet), far below 30. With
// plane edges at a width of 2 and a radius of 3 (a cage of edge length ~6), exactly those two
// lines are features: the floor and the wall end there. Nothing else: the fillet's own facets
// are planar regions too narrow to count. A faceted cylinder (32 facets of radius 1, each
// 0.2 wide) has none at any width: its facets are as wide as the facets beyond them.
TEST(Features, PlaneEdgesWhereAPlaneMeetsANarrowFillet) {
  std::vector<std::array<double, 2>> profile;  // (x, z)
  for (int i = -10; i <= 0; ++i) profile.push_back({double(i), 0.0});
  for (int k = 1; k <= 6; ++k) {
    const double a = -0.5 * 3.14159265358979323846 + k * 3.14159265358979323846 / 12;  // from -90 to 0 degrees
    profile.push_back({std::cos(a), 1 + std::sin(a)});
  }
  for (int i = 2; i <= 10; ++i) profile.push_back({1.0, double(i)});
  const int np = static_cast<int>(profile.size());
  test::MeshBuilder b;
  b.patch([&](double u, double v) {
    const auto& q = profile[static_cast<std::size_t>(std::lround(u * (np - 1)))];
    return P3{q[0], 10 * v, q[1]};
  }, np - 1, 10);
  MeshInput mesh = b.mesh();
  FeatureOptions options;
  set_plane_regions(mesh, 2, options);
  options.plane_radius = 3;
  const FeatureSet fs = detect_features(mesh, options);
  int floor_line = 0, wall_line = 0, other = 0;
  for (const auto& e : fs.edges) {
    const P3 &p = mesh.positions[e[0]], &q = mesh.positions[e[1]];
    const bool along_y = p[0] == q[0] && p[2] == q[2];
    if (along_y && p[0] == 0 && p[2] == 0)
      ++floor_line;
    else if (along_y && std::abs(p[0] - 1) < 1e-12 && std::abs(p[2] - 1) < 1e-12)
      ++wall_line;
    else if (!(p[1] == q[1] && (p[1] == 0 || p[1] == 10)) && !(p[0] == q[0] && p[2] == q[2] && (p[0] == -10 || p[2] == 10)))
      ++other;  // not on the boundary
  }
  EXPECT_EQ(floor_line, 10);
  EXPECT_EQ(wall_line, 10);
  EXPECT_EQ(other, 0);
  EXPECT_EQ(fs.plane_edges, 20);
  // off by default (the remesher turns it on at its edge length)
  EXPECT_EQ(detect_features(mesh).plane_edges, 0);
  // a narrower plane_radius than the fillet's: none
  options.plane_radius = 0.9;
  EXPECT_EQ(detect_features(mesh, options).plane_edges, 0);

  const MeshInput cylinder = test::open_cylinder(1, 2, 32, 6);
  FeatureOptions fine;
  set_plane_regions(cylinder, 0.1, fine);
  fine.plane_radius = 10;
  EXPECT_EQ(fine.plane_widths.size(), 32u);  // every facet a region
  EXPECT_EQ(detect_features(cylinder, fine).plane_edges, 0);
}

TEST(Features, TaggedCreaseOnSmoothSurfaceIsKept) {
  MeshInput sphere = test::icosphere(2);
  // a chain of three edges of the first faces
  int a = sphere.face_indices[0], b = sphere.face_indices[1], c = sphere.face_indices[2];
  sphere.creases.push_back({a, b, kInfiniteSharpness});
  sphere.creases.push_back({b, c, kInfiniteSharpness});
  sphere.creases.push_back({c, a, 1.0});  // semi-sharp: not a feature
  FeatureSet fs = detect_features(sphere);
  ASSERT_EQ(fs.edges.size(), 2u);
  // the chain turns by 120 degrees at b (two sides of a triangle): a corner at the default 60
  EXPECT_EQ(fs.chains, 2);
  EXPECT_EQ(fs.corners.size(), 3u);
  FeatureOptions blunt;
  blunt.corner_angle_degrees = 150;
  FeatureSet one = detect_features(sphere, blunt);
  EXPECT_EQ(one.chains, 1);
  EXPECT_EQ(one.corners, (std::vector<int>{std::min(a, c), std::max(a, c)}));
}

// Soft features: a roof of two planes meeting at 18 degrees (below the 30-degree feature angle)
// along the line x = 0 is a feature when the bend is concentrated there at the scale asked for,
// every ridge edge and nothing else inside; an 18-sided open cylinder (20 degrees at every
// facet edge, facets 0.35 wide) is not at a scale of 0.5 (its neighbouring edges bend alike),
// but its facet edges are at a scale of 0.1 (finer than the facets). Off by default.
TEST(Features, SoftFeaturesWhereTheBendIsConcentrated) {
  const double slope = std::tan(9.0 * test::kTestPi / 180.0);  // each side 9 degrees: dihedral 18
  test::MeshBuilder roof;
  roof.patch([&](double u, double v) { return P3{2 * u - 1, 2 * v - 1, -slope * std::abs(2 * u - 1)}; }, 10, 10);
  const MeshInput ridge = roof.mesh();
  auto interior = [](const MeshInput& m, const FeatureSet& fs, const std::function<bool(const P3&, const P3&)>& expected) {
    int found = 0, wrong = 0;
    for (const auto& e : fs.edges) {
      const P3 &a = m.positions[e[0]], &b = m.positions[e[1]];
      bool boundary = false;
      for (int k = 0; k < 2; ++k) boundary |= std::abs(std::abs(a[k]) - 1) < 1e-12 && a[k] == b[k];
      if (boundary) continue;  // the open boundary
      (expected(a, b) ? found : wrong) += 1;
    }
    return std::pair<int, int>{found, wrong};
  };
  auto on_ridge = [](const P3& a, const P3& b) { return std::abs(a[0]) < 1e-12 && std::abs(b[0]) < 1e-12; };
  FeatureOptions o;
  EXPECT_EQ(interior(ridge, detect_features(ridge, o), on_ridge), (std::pair<int, int>{0, 0}));  // off
  o.soft_angle_degrees = 15;
  o.soft_reach = 0.5;
  EXPECT_EQ(interior(ridge, detect_features(ridge, o), on_ridge), (std::pair<int, int>{10, 0}));
  o.soft_angle_degrees = 20;  // above the ridge's 18 degrees
  EXPECT_EQ(interior(ridge, detect_features(ridge, o), on_ridge), (std::pair<int, int>{0, 0}));

  const MeshInput facets = test::open_cylinder(1, 2, 18, 4);
  auto none = [](const P3&, const P3&) { return false; };
  auto vertical = [](const P3& a, const P3& b) { return std::abs(a[0] - b[0]) < 1e-12 && std::abs(a[1] - b[1]) < 1e-12; };
  auto cylinder = [&](const FeatureSet& fs, const std::function<bool(const P3&, const P3&)>& expected) {
    int found = 0, wrong = 0;
    for (const auto& e : fs.edges) {
      const P3 &a = facets.positions[e[0]], &b = facets.positions[e[1]];
      if ((std::abs(a[2]) < 1e-12 && std::abs(b[2]) < 1e-12) || (std::abs(a[2] - 2) < 1e-12 && std::abs(b[2] - 2) < 1e-12))
        continue;  // the boundary loops
      (expected(a, b) ? found : wrong) += 1;
    }
    return std::pair<int, int>{found, wrong};
  };
  o.soft_angle_degrees = 15;
  o.soft_reach = 0.5;
  EXPECT_EQ(cylinder(detect_features(facets, o), none), (std::pair<int, int>{0, 0}));
  o.soft_reach = 0.1;
  EXPECT_EQ(cylinder(detect_features(facets, o), vertical), (std::pair<int, int>{18 * 4, 0}));
}

TEST(Features, NonManifoldEdgeIsRefused) {
  MeshInput m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  m.face_sizes = {3, 3, 3};
  m.face_indices = {0, 1, 2, 1, 0, 3, 0, 1, 4};
  EXPECT_THROW(detect_features(m), Error);
}

}  // namespace
}  // namespace subd2nurbs
