// Quad recovery (core/mesh/quad_recovery.h). Oracle: the quads we triangulated ourselves.
// Every all-quad 2-manifold corpus shape, each quad split along one diagonal (both choices, and
// a mix), must give back exactly its quads: the same face count and the same faces as cyclic
// vertex sequences with the same orientation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <set>
#include <string>
#include <vector>

#include "common/corpus.h"
#include "core/mesh/quad_recovery.h"
#include "core/refine/refiner.h"
#include "io/obj_reader.h"

namespace subd2nurbs {
namespace {

/// Faces as cyclic sequences rotated to start at their smallest vertex (orientation kept).
std::multiset<std::vector<int>> canonical_faces(const MeshInput& m) {
  std::multiset<std::vector<int>> faces;
  size_t o = 0;
  for (int n : m.face_sizes) {
    std::vector<int> f(m.face_indices.begin() + static_cast<long>(o), m.face_indices.begin() + static_cast<long>(o + n));
    std::rotate(f.begin(), std::min_element(f.begin(), f.end()), f.end());
    faces.insert(f);
    o += static_cast<size_t>(n);
  }
  return faces;
}

enum class Split { FirstDiagonal, SecondDiagonal, Alternating };

/// Splits every quad into two triangles along the diagonal 0-2 or 1-3 (other faces kept).
MeshInput triangulate(const MeshInput& m, Split split) {
  MeshInput t = m;
  t.face_sizes.clear();
  t.face_indices.clear();
  t.holes.clear();
  size_t o = 0;
  for (int f = 0; f < m.num_faces(); ++f) {
    const int n = m.face_sizes[f];
    const int* v = m.face_indices.data() + o;
    o += static_cast<size_t>(n);
    if (n != 4) {
      t.face_sizes.push_back(n);
      t.face_indices.insert(t.face_indices.end(), v, v + n);
      continue;
    }
    const bool second = split == Split::SecondDiagonal || (split == Split::Alternating && f % 2 == 1);
    const int s = second ? 1 : 0;
    const int a = v[s], b = v[s + 1], c = v[(s + 2) % 4], d = v[(s + 3) % 4];
    t.face_sizes.insert(t.face_sizes.end(), {3, 3});
    t.face_indices.insert(t.face_indices.end(), {a, b, c, a, c, d});
  }
  return t;
}

double angle_deg(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  const double d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const double na = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  const double nb = std::sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
  return std::acos(std::clamp(d / (na * nb), -1.0, 1.0)) * 180 / M_PI;
}
std::array<double, 3> minus(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
std::array<double, 3> cross(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

/// The domain where recovery must be exact: every quad of the cage within 35 degrees of a
/// rectangle at each corner and folded by at most 35 degrees across either diagonal (the
/// recovery's limits are 40 and 40, as Blender's "Tris to Quads" defaults).
bool reasonable_quads(const MeshInput& m) {
  for (int f = 0; f < m.num_faces(); ++f) {
    std::array<std::array<double, 3>, 4> q;
    for (int k = 0; k < 4; ++k) q[k] = m.positions[static_cast<size_t>(m.face_indices[4 * f + k])];
    for (int i = 0; i < 4; ++i)
      if (std::abs(angle_deg(minus(q[(i + 1) % 4], q[i]), minus(q[(i + 3) % 4], q[i])) - 90) > 35) return false;
    for (int s = 0; s < 2; ++s) {
      const auto& a = q[s];
      const auto& b = q[s + 1];
      const auto& c = q[(s + 2) % 4];
      const auto& d = q[(s + 3) % 4];
      if (angle_deg(cross(minus(b, a), minus(c, a)), cross(minus(c, a), minus(d, a))) > 35) return false;
    }
  }
  return true;
}

struct Shapes {
  std::vector<std::string> reasonable, other;
};

/// The all-quad 2-manifold corpus shapes, split by reasonable_quads.
const Shapes& all_quad_corpus_shapes() {
  static const Shapes shapes = [] {
    Shapes s;
    for (const auto& e : std::filesystem::directory_iterator(SUBD2NURBS_CORPUS_DIR)) {
      if (e.path().extension() != ".obj") continue;
      const std::string name = e.path().stem().string();
      if (testing::non_manifold_corpus_shapes().count(name)) continue;
      const LoadedCage cage = read_obj(e.path().string());
      const auto& sizes = cage.input.face_sizes;
      if (!std::all_of(sizes.begin(), sizes.end(), [](int n) { return n == 4; })) continue;
      (reasonable_quads(cage.input) ? s.reasonable : s.other).push_back(name);
    }
    std::sort(s.reasonable.begin(), s.reasonable.end());
    std::sort(s.other.begin(), s.other.end());
    return s;
  }();
  return shapes;
}

class TriangulatedCorpus : public ::testing::TestWithParam<std::string> {};

TEST_P(TriangulatedCorpus, RecoversExactlyTheOriginalQuads) {
  const LoadedCage cage = read_obj(std::string(SUBD2NURBS_CORPUS_DIR) + "/" + GetParam() + ".obj");
  const auto original = canonical_faces(cage.input);
  for (Split split : {Split::FirstDiagonal, Split::SecondDiagonal, Split::Alternating}) {
    SCOPED_TRACE(static_cast<int>(split));
    const MeshInput tri = triangulate(cage.input, split);
    ASSERT_EQ(tri.num_faces(), 2 * cage.input.num_faces());
    const QuadRecoveryResult r = recover_quads(tri);
    EXPECT_EQ(r.input_triangles, tri.num_faces());
    EXPECT_EQ(r.quads, cage.input.num_faces());
    EXPECT_EQ(r.triangles_kept, 0);
    EXPECT_EQ(r.fan_vertices, 0);
    EXPECT_EQ(r.mesh.num_faces(), cage.input.num_faces());
    EXPECT_EQ(canonical_faces(r.mesh), original);
    EXPECT_EQ(r.sources.size(), static_cast<size_t>(r.mesh.num_faces()));
  }
}

INSTANTIATE_TEST_SUITE_P(OpenSubdiv, TriangulatedCorpus, ::testing::ValuesIn(all_quad_corpus_shapes().reasonable),
                         [](const ::testing::TestParamInfo<std::string>& p) { return p.param; });

// Cages with quads far from rectangular or strongly folded (catmark_car: corners 82 degrees
// off, folds up to 134 degrees) are outside the domain: recovery is partial there. It must
// still account for every triangle once and give a valid cage.
class TriangulatedOddCorpus : public ::testing::TestWithParam<std::string> {};

TEST_P(TriangulatedOddCorpus, EveryTriangleEndsInOneFaceAndTheCageIsValid) {
  const LoadedCage cage = read_obj(std::string(SUBD2NURBS_CORPUS_DIR) + "/" + GetParam() + ".obj");
  const MeshInput tri = triangulate(cage.input, Split::Alternating);
  const QuadRecoveryResult r = recover_quads(tri);
  EXPECT_EQ(2 * r.quads + r.triangles_kept, tri.num_faces());
  EXPECT_EQ(r.mesh.num_faces(), r.quads + r.triangles_kept);
  std::vector<int> used(static_cast<size_t>(tri.num_faces()), 0);
  for (const auto& s : r.sources)
    for (int f : s) ++used[static_cast<size_t>(f)];
  EXPECT_TRUE(std::all_of(used.begin(), used.end(), [](int n) { return n == 1; }));
  EXPECT_NO_THROW(SubdivLevel::from_input(r.mesh));
  std::cout << "[ recovery ] " << GetParam() << ": " << r.quads << " of " << cage.input.num_faces()
            << " quads, " << r.fan_vertices << " fan vertices\n";
}

INSTANTIATE_TEST_SUITE_P(OpenSubdiv, TriangulatedOddCorpus, ::testing::ValuesIn(all_quad_corpus_shapes().other),
                         [](const ::testing::TestParamInfo<std::string>& p) { return p.param; });

TEST(QuadRecovery, TheCorpusHasEnoughReasonableQuadShapes) {
  EXPECT_GE(all_quad_corpus_shapes().reasonable.size(), 30u);
}

/// A disc: an n-triangle fan around the origin inside a ring of n quads (triangulated).
MeshInput fan_in_a_ring(int n) {
  MeshInput m;
  m.positions.push_back({0, 0, 0});
  for (int ring = 1; ring <= 2; ++ring)
    for (int k = 0; k < n; ++k) {
      const double t = 2 * M_PI * k / n;
      m.positions.push_back({ring * std::cos(t), ring * std::sin(t), 0});
    }
  auto inner = [n](int k) { return 1 + (k % n); };
  auto outer = [n](int k) { return 1 + n + (k % n); };
  for (int k = 0; k < n; ++k) {
    m.face_sizes.push_back(3);
    m.face_indices.insert(m.face_indices.end(), {0, inner(k), inner(k + 1)});
  }
  for (int k = 0; k < n; ++k) {
    m.face_sizes.insert(m.face_sizes.end(), {3, 3});
    m.face_indices.insert(m.face_indices.end(),
                          {inner(k), outer(k), outer(k + 1), inner(k), outer(k + 1), inner(k + 1)});
  }
  return m;
}

TEST(QuadRecovery, KeepsTheFanAroundAPoleAsTriangles) {
  for (int n : {6, 8, 12, 64}) {
    SCOPED_TRACE(n);
    const QuadRecoveryResult r = recover_quads(fan_in_a_ring(n));
    EXPECT_EQ(r.fan_vertices, 1);
    EXPECT_EQ(r.fan_triangles, n);
    EXPECT_EQ(r.triangles_kept, n);
    EXPECT_EQ(r.quads, n);  // the ring, whose quads are trapezoids close to rectangles for n >= 6
    EXPECT_EQ(r.mesh.num_faces(), 2 * n);
  }
}

TEST(QuadRecovery, RejectsFoldedAndThinPairs) {
  const QuadRecoveryOptions o;
  // A unit square: perfect.
  EXPECT_DOUBLE_EQ(quad_quality({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, o), 1.0);
  // Folded by 90 degrees across the diagonal 0-2 (two faces of a cube corner): rejected.
  EXPECT_LE(quad_quality({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {1, 1, 1}, o), 0.0);
  // Not convex (an arrow head).
  EXPECT_LE(quad_quality({0, 0, 0}, {2, 1, 0}, {0, 2, 0}, {0.5, 1, 0}, o), 0.0);
  // A thin rhombus, 30 degree corners.
  const double c = std::cos(M_PI / 6), s = std::sin(M_PI / 6);
  EXPECT_LE(quad_quality({0, 0, 0}, {1, 0, 0}, {1 + c, s, 0}, {c, s, 0}, o), 0.0);
  // Clockwise: the same square seen from below is fine too (orientation is not a shape flaw).
  EXPECT_DOUBLE_EQ(quad_quality({0, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}, o), 1.0);
}

TEST(QuadRecovery, CarriesTagsAndOtherFaces) {
  // Two unit squares side by side, each split along a diagonal; a triangle roof on the right
  // square (it would make a kite with either neighbour); a separate pentagon.
  MeshInput m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}, {1, 1, 0}, {2, 1, 0}, {1.5, 2, 0},
                 {5, 0, 0}, {6, 0, 0}, {6.5, 1, 0}, {5.5, 2, 0}, {4.5, 1, 0}};
  m.face_sizes = {3, 3, 3, 3, 3, 5};
  m.face_indices = {0, 1, 4, 0, 4, 3, 1, 2, 5, 1, 5, 4, 4, 5, 6, 7, 8, 9, 10, 11};
  // Tags: a crease on the real edge 1-4, one on the diagonal 0-4, a hole on face 2.
  m.creases = {{1, 4, 2.0}, {0, 4, 3.0}};
  m.holes = {2};
  const QuadRecoveryResult r = recover_quads(m);
  EXPECT_EQ(r.input_triangles, 5);
  EXPECT_EQ(r.quads, 2);
  EXPECT_EQ(r.triangles_kept, 1);
  EXPECT_EQ(r.other_faces, 1);
  ASSERT_EQ(r.mesh.num_faces(), 4);
  EXPECT_EQ(r.mesh.face_sizes, (std::vector<int>{4, 4, 3, 5}));
  ASSERT_EQ(r.mesh.creases.size(), 1u);
  EXPECT_EQ(r.mesh.creases[0].v0, 1);
  EXPECT_EQ(r.mesh.creases[0].v1, 4);
  ASSERT_EQ(r.mesh.holes.size(), 1u);
  EXPECT_EQ(r.mesh.holes[0], 1);  // the second quad, from faces 2 and 3
  EXPECT_EQ(r.sources[1], (std::vector<int>{2, 3}));
  EXPECT_EQ(canonical_faces(r.mesh).count({0, 1, 4, 3}), 1u);
  EXPECT_EQ(canonical_faces(r.mesh).count({1, 2, 5, 4}), 1u);
}

}  // namespace
}  // namespace subd2nurbs
