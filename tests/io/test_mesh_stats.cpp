// compute_stats on small cages whose numbers can be counted by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "core/analysis/mesh_stats.h"
#include "io/obj_reader.h"
#include "io/temp_dir.h"

using namespace subd2nurbs;
using subd2nurbs::testing::TempDir;

namespace {

MeshStats stats_of(const std::string& path) {
  const LoadedCage cage = read_obj(path);
  const SubdivLevel level = SubdivLevel::from_input(cage.input);
  return compute_stats(level, {cage.input.positions.begin(), cage.input.positions.end()});
}

std::string valid(const std::string& name) {
  return std::string(SUBD2NURBS_TEST_DATA_DIR) + "/valid/" + name;
}

// 3x2 quads; tag lines are appended per test.
const std::string kGrid =
    "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nv 1 1 0\nv 2 1 0\nv 3 1 0\nv 0 2 0\nv 1 2 0\n"
    "v 2 2 0\nv 3 2 0\nv 3 0 0\n"
    "f 1 2 5 4\nf 2 3 6 5\nf 3 12 7 6\nf 4 5 9 8\nf 5 6 10 9\nf 6 7 11 10\n";

}  // namespace

TEST(MeshStats, RoundedBoxSample) {
  const MeshStats s = stats_of(std::string(SUBD2NURBS_SAMPLES_DIR) + "/rounded_box.obj");
  EXPECT_EQ(s.vertices, 26);
  EXPECT_EQ(s.faces, 24);
  EXPECT_EQ(s.edges, 48);
  EXPECT_EQ(s.corners, 96);
  EXPECT_EQ(s.face_sizes, (std::map<int, int>{{4, 24}}));
  EXPECT_EQ(s.valences, (std::map<int, int>{{3, 8}, {4, 18}}));
  EXPECT_TRUE(s.closed);
  EXPECT_EQ(s.boundary_edges, 0);
  EXPECT_EQ(s.boundary_loops, 0);
  EXPECT_EQ(s.euler_characteristic, 2);
  EXPECT_EQ(s.components, 1);
  EXPECT_EQ(s.extraordinary_vertices, 8);  // the cube's corners, valence 3
  EXPECT_EQ(s.semi_sharp_crease_edges, 8);
  EXPECT_EQ(s.infinite_crease_edges, 0);
  EXPECT_EQ(s.corner_vertices, 0);
  EXPECT_EQ(s.holes, 0);
  EXPECT_EQ(s.bounds.min, (Point3{-1, -1, -1}));
  EXPECT_EQ(s.bounds.max, (Point3{1, 1, 1}));
  EXPECT_DOUBLE_EQ(s.bounds.diagonal, 2 * std::sqrt(3.0));
}

TEST(MeshStats, OpenGridWithTags) {
  const MeshStats s = stats_of(valid("all_tags.obj"));  // kGrid with every tag, EdgeOnly
  EXPECT_EQ(s.vertices, 12);
  EXPECT_EQ(s.edges, 17);
  EXPECT_FALSE(s.closed);
  EXPECT_EQ(s.boundary_edges, 10);
  EXPECT_EQ(s.boundary_vertices, 10);
  EXPECT_EQ(s.boundary_loops, 1);
  EXPECT_EQ(s.topological_corners, 4);
  EXPECT_EQ(s.valences, (std::map<int, int>{{2, 4}, {3, 6}, {4, 2}}));
  EXPECT_EQ(s.extraordinary_vertices, 0);
  EXPECT_EQ(s.euler_characteristic, 1);
  EXPECT_EQ(s.semi_sharp_crease_edges, 2);
  EXPECT_EQ(s.corner_vertices, 3);  // under EdgeOnly the tagged topological corner counts
  EXPECT_EQ(s.holes, 2);
}

TEST(MeshStats, AutomaticCornersAreNotCornerVertices) {
  TempDir dir;
  // Default rule: the 4 topological corners are sharp by rule; vertex 1 (0-based) by tag;
  // the interior edge 4-5 (0-based) infinitely sharp.
  const MeshStats s = stats_of(
      dir.write("g.obj", kGrid + "t corner 1/1/0 1 2\nt corner 1/1/0 0 10\nt crease 2/1/0 4 5 10\n"));
  EXPECT_EQ(s.topological_corners, 4);
  EXPECT_EQ(s.corner_vertices, 1);
  EXPECT_EQ(s.infinite_crease_edges, 1);
  EXPECT_EQ(s.semi_sharp_crease_edges, 0);
}

TEST(MeshStats, ExtraordinaryVertices) {
  TempDir dir;
  // Three quads around vertex 1, which is interior with valence 3.
  const MeshStats s = stats_of(dir.write(
      "fan.obj",
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -1 0 0\nv -1 -1 0\nv 0 -1 0\n"
      "f 1 2 3 4\nf 1 4 5 6\nf 1 6 7 2\n"));
  // Vertex 1: interior, valence 3 -> extraordinary. Rim vertices 2, 4, 6: boundary, valence 3
  // -> regular. Rim vertices 3, 5, 7: topological corners -> regular.
  EXPECT_EQ(s.extraordinary_vertices, 1);
  EXPECT_EQ(s.topological_corners, 3);
  EXPECT_EQ(s.boundary_loops, 1);
}

TEST(MeshStats, UnusedVerticesAndComponents) {
  const MeshStats unused = stats_of(valid("unused_vertex.obj"));
  EXPECT_EQ(unused.unused_vertices, 1);
  EXPECT_EQ(unused.bounds.max, (Point3{1, 1, 0}));  // the unused vertex (5,5,5) is not counted
  EXPECT_EQ(unused.euler_characteristic, 1);

  TempDir dir;
  const MeshStats two = stats_of(dir.write(
      "two.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 5 0 0\nv 6 0 0\nv 6 1 0\n"
                 "f 1 2 3 4\nf 5 6 7\n"));
  EXPECT_EQ(two.components, 2);
  EXPECT_EQ(two.boundary_loops, 2);
  EXPECT_EQ(two.face_sizes, (std::map<int, int>{{3, 1}, {4, 1}}));
  EXPECT_EQ(two.euler_characteristic, 2);
}

TEST(MeshStats, TorusHasEulerCharacteristicZero) {
  const MeshStats s = stats_of(std::string(SUBD2NURBS_CORPUS_DIR) + "/catmark_torus.obj");
  EXPECT_TRUE(s.closed);
  EXPECT_EQ(s.euler_characteristic, 0);
  EXPECT_EQ(s.components, 1);
}

TEST(MeshStats, PositionCountMustMatch) {
  const LoadedCage cage = read_obj(valid("unused_vertex.obj"));
  const SubdivLevel level = SubdivLevel::from_input(cage.input);
  EXPECT_THROW(compute_stats(level, {}), std::invalid_argument);
}
