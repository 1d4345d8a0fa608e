// PolyMesh connectivity and the validation errors that need no file (the OBJ-level ones,
// with line numbers, live in tests/io).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <limits>

#include "common/shapes.h"
#include "core/mesh/validate.h"

using namespace subd2nurbs;
using namespace subd2nurbs::testing;

namespace {

MeshErrorCode error_of(const MeshInput& m) {
  try {
    validate_and_build(m);
  } catch (const InvalidMeshError& e) {
    return e.code();
  }
  ADD_FAILURE() << "no error thrown";
  return MeshErrorCode::EmptyMesh;
}

/// Checks the invariants every PolyMesh must satisfy.
void expect_consistent(const PolyMesh& m) {
  for (int h = 0; h < m.num_corners(); ++h) {
    int t = m.twin(h);
    if (t >= 0) {
      EXPECT_EQ(m.twin(t), h);
      EXPECT_EQ(m.corner_vertex(t), m.to_vertex(h));
      EXPECT_EQ(m.to_vertex(t), m.corner_vertex(h));
      EXPECT_EQ(m.corner_edge(t), m.corner_edge(h));
    }
    EXPECT_EQ(m.prev(m.next(h)), h);
  }
  for (int v = 0; v < m.num_vertices(); ++v) {
    const int* c = m.vertex_corners(v);
    for (int i = 0; i < m.vertex_face_count(v); ++i) {
      EXPECT_EQ(m.corner_vertex(c[i]), v);
      if (i + 1 < m.vertex_face_count(v)) EXPECT_EQ(m.twin(m.prev(c[i])), c[i + 1]) << "fan order at " << v;
    }
  }
  for (int e = 0; e < m.num_edges(); ++e)
    EXPECT_EQ(m.find_edge(m.edge_vertex(e, 1), m.edge_vertex(e, 0)), e);
}

}  // namespace

TEST(PolyMesh, CubeCountsAndFans) {
  PolyMesh m = validate_and_build(cube());
  EXPECT_EQ(m.num_vertices(), 8);
  EXPECT_EQ(m.num_faces(), 6);
  EXPECT_EQ(m.num_edges(), 12);
  EXPECT_EQ(m.num_corners(), 24);
  for (int v = 0; v < 8; ++v) {
    EXPECT_EQ(m.valence(v), 3);
    EXPECT_FALSE(m.is_boundary_vertex(v));
  }
  for (int e = 0; e < 12; ++e) EXPECT_FALSE(m.is_boundary_edge(e));
  expect_consistent(m);
}

TEST(PolyMesh, GridBoundary) {
  PolyMesh m = validate_and_build(grid(3, 2));
  EXPECT_EQ(m.num_vertices(), 12);
  EXPECT_EQ(m.num_edges(), 3 * 3 + 4 * 2);
  int boundary_edges = 0;
  for (int e = 0; e < m.num_edges(); ++e) boundary_edges += m.is_boundary_edge(e);
  EXPECT_EQ(boundary_edges, 2 * 3 + 2 * 2);
  EXPECT_EQ(m.valence(0), 2);   // corner
  EXPECT_EQ(m.valence(1), 3);   // boundary
  EXPECT_EQ(m.valence(5), 4);   // interior
  EXPECT_TRUE(m.is_boundary_vertex(0));
  EXPECT_FALSE(m.is_boundary_vertex(5));
  // The fan of a boundary vertex starts at its outgoing boundary halfedge.
  EXPECT_LT(m.twin(m.vertex_corners(1)[0]), 0);
  expect_consistent(m);
}

TEST(PolyMesh, NgonAndHighValence) {
  PolyMesh m = validate_and_build(star(11));
  EXPECT_EQ(m.valence(0), 11);
  EXPECT_EQ(m.face_size(11), 22);
  expect_consistent(m);
}

TEST(PolyMesh, TrianglesAndPentagonsAveragingFourCornersAreNotQuads) {
  // A triangle and a pentagon glued along one edge: 8 corners on 2 faces, as two quads would
  // have. Found by fuzz_convert (tests/fuzz/regressions/fuzz_convert/pillows_3_4_5.obj): the
  // mesh was taken for all quads, its connectivity was wrong and refinement wrote out of bounds.
  MeshInput in;
  in.positions = {{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {1, -1, 0}, {0.5, -1.5, 0}, {0, -1, 0}};
  in.face_sizes = {3, 5};
  in.face_indices = {0, 1, 2, 1, 0, 5, 4, 3};
  const PolyMesh m = validate_and_build(in);
  EXPECT_FALSE(m.all_quads());
  EXPECT_EQ(m.num_edges(), 7);
  EXPECT_EQ(m.face_size(0), 3);
  EXPECT_EQ(m.corner_face(4), 1);
  EXPECT_EQ(m.next(2), 0);
  int boundary_edges = 0;
  for (int e = 0; e < m.num_edges(); ++e) boundary_edges += m.is_boundary_edge(e);
  EXPECT_EQ(boundary_edges, 6);
  expect_consistent(m);
}

TEST(PolyMesh, UnusedVertexIsAWarning) {
  MeshInput m = cube();
  m.positions.push_back({5, 5, 5});
  Diagnostics d;
  validate_and_build(m, &d);
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].code, "unused-vertex");
  EXPECT_EQ(d[0].index, 8);
}

TEST(Validation, EachErrorIsDetected) {
  MeshInput empty;
  EXPECT_EQ(error_of(empty), MeshErrorCode::EmptyMesh);

  MeshInput nan = cube();
  nan.positions[3][1] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(error_of(nan), MeshErrorCode::NonFiniteCoordinate);

  MeshInput inf = cube();
  inf.positions[2][0] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(error_of(inf), MeshErrorCode::NonFiniteCoordinate);

  MeshInput small = cube();
  add_face(small, {0, 1});
  EXPECT_EQ(error_of(small), MeshErrorCode::FaceTooSmall);

  MeshInput range = cube();
  range.face_indices[5] = 8;
  EXPECT_EQ(error_of(range), MeshErrorCode::IndexOutOfRange);

  MeshInput repeated = grid(1, 1);
  repeated.face_indices = {0, 1, 1, 2};
  EXPECT_EQ(error_of(repeated), MeshErrorCode::RepeatedVertexInFace);

  MeshInput nonman_edge = grid(1, 1);  // three quads on edge (0,1)
  nonman_edge.positions.push_back({0, -1, 0});
  nonman_edge.positions.push_back({1, -1, 0});
  nonman_edge.positions.push_back({0, 0, 1});
  nonman_edge.positions.push_back({1, 0, 1});
  add_face(nonman_edge, {1, 0, 4, 5});
  add_face(nonman_edge, {1, 0, 6, 7});
  EXPECT_EQ(error_of(nonman_edge), MeshErrorCode::NonManifoldEdge);

  MeshInput flipped = grid(2, 1);
  std::swap(flipped.face_indices[5], flipped.face_indices[7]);  // reverse the second quad
  EXPECT_EQ(error_of(flipped), MeshErrorCode::InconsistentOrientation);

  MeshInput bowtie;  // two triangles sharing only vertex 0
  bowtie.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}};
  add_face(bowtie, {0, 1, 2});
  add_face(bowtie, {0, 3, 4});
  EXPECT_EQ(error_of(bowtie), MeshErrorCode::NonManifoldVertex);

  MeshInput cone;  // interior vertex whose faces form two separate closed fans
  // Two tetrahedra-like closed fans glued at vertex 0: build two closed pyramids sharing apex.
  cone.positions = {{0, 0, 0}, {1, 0, -1}, {0, 1, -1}, {-1, -1, -1}, {1, 0, 1}, {0, 1, 1}, {-1, -1, 1}};
  add_face(cone, {0, 1, 2});
  add_face(cone, {0, 2, 3});
  add_face(cone, {0, 3, 1});
  add_face(cone, {1, 3, 2});
  add_face(cone, {0, 5, 4});
  add_face(cone, {0, 6, 5});
  add_face(cone, {0, 4, 6});
  add_face(cone, {4, 5, 6});
  EXPECT_EQ(error_of(cone), MeshErrorCode::NonManifoldVertex);

  MeshInput bad_crease = cube();
  bad_crease.creases.push_back({0, 7, 2.0});
  EXPECT_EQ(error_of(bad_crease), MeshErrorCode::InvalidTag);

  MeshInput bad_hole = cube();
  bad_hole.holes.push_back(6);
  EXPECT_EQ(error_of(bad_hole), MeshErrorCode::InvalidTag);
}

TEST(Validation, ErrorNamesTheElement) {
  MeshInput range = cube();
  range.face_indices[5] = 42;  // face 1, second corner
  try {
    validate_and_build(range);
    FAIL();
  } catch (const InvalidMeshError& e) {
    EXPECT_EQ(e.element(), ElementKind::Face);
    EXPECT_EQ(e.index(), 1);
    EXPECT_NE(std::string(e.what()).find("vertex 42"), std::string::npos) << e.what();
  }
}

namespace {

/// A band of n quads around a circle (2 n vertices); `twist`: the last quad joins the two rows
/// crosswise (a Moebius strip), else straight (an annulus).
void band(int n, bool twist, std::vector<int>& sizes, std::vector<int>& indices) {
  for (int k = 0; k < n; ++k) {
    const int a = 2 * k, b = 2 * k + 1;
    int c = 2 * ((k + 1) % n), d = c + 1;
    if (twist && k + 1 == n) std::swap(c, d);
    sizes.push_back(4);
    indices.insert(indices.end(), {a, c, d, b});
  }
}

}  // namespace

// #32 item 6: a non-orientable surface is told apart from a merely inconsistent orientation.
// Oracle: topology (a Moebius strip has no orientation; an annulus or a cube with faces
// reversed has one), independent of the face order.
TEST(PolyMesh, FacesOrientable) {
  std::vector<int> sizes, indices;
  band(8, true, sizes, indices);
  EXPECT_FALSE(faces_orientable(sizes, indices));
  sizes.clear();
  indices.clear();
  band(8, false, sizes, indices);
  EXPECT_TRUE(faces_orientable(sizes, indices));
  // Reversing every other quad of the annulus leaves it orientable (reverse them back).
  for (int f = 0; f < 8; f += 2) std::reverse(indices.begin() + 4 * f, indices.begin() + 4 * f + 4);
  EXPECT_TRUE(faces_orientable(sizes, indices));
  // The Moebius strip stays non-orientable whichever of its faces are reversed.
  sizes.clear();
  indices.clear();
  band(8, true, sizes, indices);
  for (int f = 1; f < 8; f += 3) std::reverse(indices.begin() + 4 * f, indices.begin() + 4 * f + 4);
  EXPECT_FALSE(faces_orientable(sizes, indices));
  // Its message says so; the annulus with a face reversed keeps the old one.
  MeshInput strip;
  for (int k = 0; k < 16; ++k) strip.positions.push_back({std::cos(k * 0.4), std::sin(k * 0.4), 0.1 * (k % 2)});
  strip.face_sizes = sizes;
  strip.face_indices = indices;
  try {
    validate_and_build(strip);
    ADD_FAILURE() << "the Moebius strip was accepted";
  } catch (const InvalidMeshError& e) {
    EXPECT_EQ(e.code(), MeshErrorCode::InconsistentOrientation);
    EXPECT_NE(std::string(e.what()).find("the surface is not orientable"), std::string::npos) << e.what();
  }
}
