// write_obj: what it writes, and that reading it back gives the same level.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <map>
#include <stdexcept>

#include "io/input_error.h"
#include "io/obj_reader.h"
#include "io/obj_writer.h"
#include "io/temp_dir.h"

using namespace subd2nurbs;
using subd2nurbs::testing::read_text;
using subd2nurbs::testing::TempDir;

namespace {

std::string corpus(const std::string& name) {
  return std::string(SUBD2NURBS_CORPUS_DIR) + "/" + name + ".obj";
}
std::string valid(const std::string& name) {
  return std::string(SUBD2NURBS_TEST_DATA_DIR) + "/valid/" + name;
}

std::vector<Point3> positions_of(const LoadedCage& cage) {
  return {cage.input.positions.begin(), cage.input.positions.end()};
}

bool same_bits(const std::vector<Point3>& a, const std::vector<Point3>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Point3)) == 0;
}

std::vector<int> faces_of(const PolyMesh& m) {
  std::vector<int> out;
  for (int f = 0; f < m.num_faces(); ++f) {
    out.push_back(-m.face_size(f));  // separator carrying the size
    out.insert(out.end(), m.face_vertices(f), m.face_vertices(f) + m.face_size(f));
  }
  return out;
}

/// Edge sharpness by edge (its two vertices): edge numbering differs between a refined level
/// (numbered by the refiner) and the same faces read back (numbered by PolyMesh::build).
std::map<std::pair<int, int>, float> sharpness_by_edge(const SubdivLevel& level) {
  std::map<std::pair<int, int>, float> out;
  for (int e = 0; e < level.mesh.num_edges(); ++e) {
    const int a = level.mesh.edge_vertex(e, 0), b = level.mesh.edge_vertex(e, 1);
    out[{std::min(a, b), std::max(a, b)}] = level.edge_sharpness[e];
  }
  return out;
}

/// Everything a level consists of, compared exactly.
void expect_same_level(const SubdivLevel& a, const SubdivLevel& b, const std::string& what) {
  EXPECT_EQ(faces_of(a.mesh), faces_of(b.mesh)) << what;
  EXPECT_EQ(a.mesh.num_vertices(), b.mesh.num_vertices()) << what;
  EXPECT_EQ(a.options.boundary, b.options.boundary) << what;
  EXPECT_EQ(a.options.crease_method, b.options.crease_method) << what;
  EXPECT_EQ(a.options.triangles, b.options.triangles) << what;
  EXPECT_EQ(sharpness_by_edge(a), sharpness_by_edge(b)) << what;
  EXPECT_EQ(a.vertex_sharpness, b.vertex_sharpness) << what;
  EXPECT_EQ(a.face_hole, b.face_hole) << what;
}

std::vector<std::string> valid_corpus_shapes() {
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(SUBD2NURBS_CORPUS_DIR)) {
    if (e.path().extension() != ".obj") continue;
    try {
      validate_cage(read_obj(e.path().string()));
      names.push_back(e.path().stem().string());
    } catch (const InputError&) {
      // non-manifold shapes: see test_corpus_reading.cpp
    }
  }
  std::sort(names.begin(), names.end());
  return names;
}

int count_lines_starting(const std::string& text, const std::string& prefix) {
  int n = 0;
  for (size_t pos = 0; pos < text.size();) {
    if (text.compare(pos, prefix.size(), prefix) == 0) ++n;
    pos = text.find('\n', pos);
    if (pos == std::string::npos) break;
    ++pos;
  }
  return n;
}

class RoundTrip : public ::testing::TestWithParam<std::string> {};

}  // namespace

TEST(ObjWriter, WritesTagsThatReproduceTheLevel) {
  const LoadedCage cage = read_obj(valid("all_tags.obj"));
  const SubdivLevel level = SubdivLevel::from_input(cage.input);
  TempDir dir;
  const std::string path = dir.file("out.obj");
  write_obj(path, positions_of(cage), level);
  const std::string text = read_text(path);

  EXPECT_EQ(text.rfind("# Written by subd2nurbs", 0), 0u);
  EXPECT_EQ(count_lines_starting(text, "v "), 12);
  EXPECT_EQ(count_lines_starting(text, "f "), 6);
  EXPECT_NE(text.find("\nf 3 12 7 6\n"), std::string::npos);
  EXPECT_NE(text.find("\nt interpolateboundary 1/0/0 2\n"), std::string::npos);
  EXPECT_NE(text.find("\nt creasemethod 0/0/1 chaikin\n"), std::string::npos);
  EXPECT_NE(text.find("\nt smoothtriangles 0/0/1 smooth\n"), std::string::npos);
  EXPECT_NE(text.find("\nt crease 2/1/0 3 4 1.5\n"), std::string::npos);
  EXPECT_NE(text.find("\nt crease 2/1/0 4 5 2.5\n"), std::string::npos);
  // Only interior edges: boundary edges are sharp without a tag.
  EXPECT_EQ(count_lines_starting(text, "t crease "), 2);
  // Under EdgeOnly a topological corner keeps its explicit tag (vertices 0 and 10).
  EXPECT_NE(text.find("\nt corner 1/1/0 0 10\n"), std::string::npos);
  EXPECT_NE(text.find("\nt corner 1/1/0 2 10\n"), std::string::npos);
  EXPECT_NE(text.find("\nt corner 1/1/0 10 3\n"), std::string::npos);
  EXPECT_EQ(count_lines_starting(text, "t corner"), 3);
  EXPECT_NE(text.find("\nt hole 1/0/0 4\n"), std::string::npos);
  EXPECT_NE(text.find("\nt hole 1/0/0 5\n"), std::string::npos);

  const LoadedCage again = read_obj(path);
  EXPECT_TRUE(again.diagnostics.empty());
  expect_same_level(level, SubdivLevel::from_input(again.input), "all_tags.obj");
}

TEST(ObjWriter, AutomaticCornersAreNotWrittenAsTags) {
  // Default rule (edge and corner): the quad's four corners are sharpened by the rule itself.
  TempDir dir;
  const LoadedCage cage = read_obj(
      dir.write("quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n"));
  const SubdivLevel level = SubdivLevel::from_input(cage.input);
  ASSERT_EQ(std::count(level.vertex_sharpness.begin(), level.vertex_sharpness.end(), 0.0), 0);
  write_obj(dir.file("out.obj"), positions_of(cage), level);
  const std::string text = read_text(dir.file("out.obj"));
  EXPECT_EQ(count_lines_starting(text, "t corner"), 0) << text;
  EXPECT_NE(text.find("\nt interpolateboundary 1/0/0 1\n"), std::string::npos);
  EXPECT_EQ(text.find("creasemethod"), std::string::npos);
  EXPECT_EQ(text.find("smoothtriangles"), std::string::npos);
  expect_same_level(level, SubdivLevel::from_input(read_obj(dir.file("out.obj")).input), "quad");
}

TEST(ObjWriter, UnusedVerticesNeedNoCornerTag) {
  const LoadedCage cage = read_obj(valid("unused_vertex.obj"));
  Diagnostics diagnostics;
  const SubdivLevel level = SubdivLevel::from_input(cage.input, &diagnostics);
  TempDir dir;
  write_obj(dir.file("out.obj"), positions_of(cage), level);
  const std::string text = read_text(dir.file("out.obj"));
  EXPECT_EQ(count_lines_starting(text, "t corner"), 0) << text;
  EXPECT_NE(text.find("\nv 5 5 5\n"), std::string::npos);  // still written, as vertex 5
  expect_same_level(level, SubdivLevel::from_input(read_obj(dir.file("out.obj")).input, &diagnostics),
                    "unused_vertex.obj");
}

TEST(ObjWriter, BoundaryRuleNoneWritesBoundaryCreasesAndHoles) {
  // Under "none" an untagged boundary would turn its faces into holes again on reading, so
  // the boundary is written as infinitely sharp creases and the holes explicitly.
  TempDir dir;
  const LoadedCage cage = read_obj(
      dir.write("none.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n"
                            "t interpolateboundary 1/0/0 0\n"));
  const SubdivLevel level = SubdivLevel::from_input(cage.input);
  ASSERT_EQ(level.face_hole, (std::vector<char>{1}));
  write_obj(dir.file("out.obj"), positions_of(cage), level);
  const std::string text = read_text(dir.file("out.obj"));
  EXPECT_EQ(count_lines_starting(text, "t crease 2/1/0 "), 4) << text;
  EXPECT_NE(text.find("\nt crease 2/1/0 0 1 10\n"), std::string::npos) << text;
  EXPECT_NE(text.find("\nt hole 1/0/0 0\n"), std::string::npos) << text;
  expect_same_level(level, SubdivLevel::from_input(read_obj(dir.file("out.obj")).input), "none");
}

TEST(ObjWriter, MismatchedPositionsAreRejectedAndNothingIsWritten) {
  const LoadedCage cage = read_obj(valid("all_tags.obj"));
  const SubdivLevel level = SubdivLevel::from_input(cage.input);
  std::vector<Point3> positions = positions_of(cage);
  positions.pop_back();
  TempDir dir;
  EXPECT_THROW(write_obj(dir.file("out.obj"), positions, level), std::invalid_argument);
  EXPECT_TRUE(dir.entries().empty());
}

TEST(ObjWriter, UnwritableLocationThrowsWriteError) {
  const LoadedCage cage = read_obj(valid("all_tags.obj"));
  const SubdivLevel level = SubdivLevel::from_input(cage.input);
  TempDir dir;
  EXPECT_THROW(write_obj(dir.file("missing/out.obj"), positions_of(cage), level), WriteError);
  EXPECT_TRUE(dir.entries().empty());
}

TEST_P(RoundTrip, BaseAndRefinedLevelsSurviveWriteAndRead) {
  const LoadedCage cage = read_obj(corpus(GetParam()));
  const SubdivLevel base = SubdivLevel::from_input(cage.input);
  const int levels = base.mesh.num_faces() > 2000 ? 1 : 2;
  const Refinement refinement = refine_uniform(base, levels);
  const std::vector<std::vector<Point3>> positions = refinement.positions(positions_of(cage));
  TempDir dir;
  for (int k = 0; k <= levels; ++k) {
    const std::string what = GetParam() + " level " + std::to_string(k);
    const std::string path = dir.file("level" + std::to_string(k) + ".obj");
    write_obj(path, positions[k], refinement.levels[k]);
    const LoadedCage again = read_obj(path);
    EXPECT_TRUE(again.diagnostics.empty()) << what;
    EXPECT_TRUE(same_bits(positions_of(again), positions[k])) << what;
    expect_same_level(refinement.levels[k], SubdivLevel::from_input(again.input), what);
  }
}

INSTANTIATE_TEST_SUITE_P(OpenSubdivCorpus, RoundTrip, ::testing::ValuesIn(valid_corpus_shapes()),
                         [](const ::testing::TestParamInfo<std::string>& p) { return p.param; });

TEST(RoundTripCoverage, CorpusShapesWithEveryFeatureAreIncluded) {
  const std::vector<std::string> shapes = valid_corpus_shapes();
  for (const char* needed : {"catmark_chaikin1", "catmark_hole_test2", "catmark_edgenone",
                             "catmark_edgeonly", "catmark_smoothtris1", "catmark_cube_corner4",
                             "catmark_cubes_semisharp"})
    EXPECT_TRUE(std::binary_search(shapes.begin(), shapes.end(), needed)) << needed;
}
