// read_obj and validate_cage on OpenSubdiv's regression shapes.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "common/corpus.h"
#include "core/refine/refiner.h"
#include "io/obj_reader.h"

using namespace subd2nurbs;

namespace {

std::string corpus(const std::string& name) {
  return std::string(SUBD2NURBS_CORPUS_DIR) + "/" + name + ".obj";
}

std::vector<std::string> corpus_shapes() {
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(SUBD2NURBS_CORPUS_DIR))
    if (e.path().extension() == ".obj") names.push_back(e.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

/// Statement counts by the simplest possible means: the first word of each line.
struct LineCounts {
  int v = 0, f = 0, crease = 0, corner = 0;
};
LineCounts count_lines(const std::string& path) {
  LineCounts c;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string first, second;
    words >> first >> second;
    if (first == "v") ++c.v;
    if (first == "f") ++c.f;
    if (first == "t" && second == "crease") ++c.crease;  // all corpus creases are "2/1/0"
    if (first == "t" && second == "corner") ++c.corner;  // all corpus corners are "1/1/0"
  }
  return c;
}

class CorpusFile : public ::testing::TestWithParam<std::string> {};

}  // namespace

TEST(CorpusReading, HasTheWholeCorpus) { EXPECT_EQ(corpus_shapes().size(), 87u); }

TEST_P(CorpusFile, CountsMatchTheLines) {
  const std::string path = corpus(GetParam());
  const LoadedCage cage = read_obj(path);
  const LineCounts lines = count_lines(path);
  EXPECT_EQ(cage.input.num_vertices(), lines.v);
  EXPECT_EQ(cage.input.num_faces(), lines.f);
  EXPECT_EQ(static_cast<int>(cage.input.creases.size()), lines.crease);
  EXPECT_EQ(static_cast<int>(cage.input.corners.size()), lines.corner);
  EXPECT_EQ(cage.vertex_line.size(), cage.input.positions.size());
  EXPECT_EQ(cage.face_line.size(), cage.input.face_sizes.size());
  EXPECT_TRUE(std::is_sorted(cage.face_line.begin(), cage.face_line.end()));
}

TEST_P(CorpusFile, ValidatesUnlessNonManifold) {
  const LoadedCage cage = read_obj(corpus(GetParam()));
  const auto& rejected_shapes = subd2nurbs::testing::non_manifold_corpus_shapes();
  const auto rejected = rejected_shapes.find(GetParam());
  try {
    const PolyMesh mesh = validate_cage(cage);
    EXPECT_EQ(rejected, rejected_shapes.end()) << "accepted, but expected to be rejected";
    EXPECT_EQ(mesh.num_faces(), cage.input.num_faces());
  } catch (const InputError& e) {
    ASSERT_NE(rejected, rejected_shapes.end()) << e.what();
    ASSERT_TRUE(e.code().has_value()) << e.what();
    EXPECT_EQ(to_string(*e.code()), std::string(to_string(rejected->second))) << e.what();
    EXPECT_GT(e.line(), 0) << e.what();
    EXPECT_NE(std::string(e.what()).find("non-manifold"), std::string::npos) << e.what();
  }
}

INSTANTIATE_TEST_SUITE_P(OpenSubdiv, CorpusFile, ::testing::ValuesIn(corpus_shapes()),
                         [](const ::testing::TestParamInfo<std::string>& p) { return p.param; });

TEST(CorpusReading, Options) {
  EXPECT_EQ(read_obj(corpus("catmark_chaikin0")).input.options.crease_method,
            CreaseMethod::Uniform);  // "t creasemethod 0/0/1 normal"
  EXPECT_EQ(read_obj(corpus("catmark_chaikin1")).input.options.crease_method, CreaseMethod::Chaikin);
  EXPECT_EQ(read_obj(corpus("catmark_chaikin2")).input.options.crease_method, CreaseMethod::Chaikin);
  EXPECT_EQ(read_obj(corpus("catmark_edgeonly")).input.options.boundary, BoundaryRule::EdgeOnly);
  EXPECT_EQ(read_obj(corpus("catmark_edgenone")).input.options.boundary, BoundaryRule::None);
  EXPECT_EQ(read_obj(corpus("catmark_edgecorner")).input.options.boundary,
            BoundaryRule::EdgeAndCorner);
  EXPECT_EQ(read_obj(corpus("catmark_smoothtris0")).input.options.triangles, TriangleRule::Catmark);
  EXPECT_EQ(read_obj(corpus("catmark_smoothtris1")).input.options.triangles, TriangleRule::Smooth);
  // No interpolateboundary tag: the default, edge and corner.
  EXPECT_EQ(read_obj(corpus("catmark_cube")).input.options.boundary, BoundaryRule::EdgeAndCorner);
}

TEST(CorpusReading, Holes) {
  EXPECT_EQ(read_obj(corpus("catmark_hole_test1")).input.holes, (std::vector<int>{1}));
  EXPECT_EQ(read_obj(corpus("catmark_hole_test2")).input.holes, (std::vector<int>{5, 6, 9, 10}));
  EXPECT_EQ(read_obj(corpus("catmark_hole_test3")).input.holes.size(), 8u);
  const SubdivLevel level = SubdivLevel::from_input(read_obj(corpus("catmark_hole_test2")).input);
  EXPECT_EQ(std::count(level.face_hole.begin(), level.face_hole.end(), 1), 4);
}

TEST(CorpusReading, CreasesAndCorners) {
  const LoadedCage cage = read_obj(corpus("catmark_edgeonly"));
  ASSERT_EQ(cage.input.corners.size(), 6u);
  EXPECT_EQ(cage.input.corners[0].vertex, 16);
  EXPECT_EQ(cage.input.corners[0].sharpness, 10.0);
  EXPECT_EQ(cage.input.corners[5].vertex, 39);
  EXPECT_EQ(cage.input.corners[5].sharpness, 2.0);

  const LoadedCage chaikin = read_obj(corpus("catmark_chaikin0"));
  ASSERT_FALSE(chaikin.input.creases.empty());
  EXPECT_EQ(chaikin.input.creases[0].v0, 0);
  EXPECT_EQ(chaikin.input.creases[0].v1, 1);
  EXPECT_EQ(chaikin.input.creases[0].sharpness, 5.0);
}

TEST(CorpusReading, UnsupportedTagsAreWarnings) {
  // catmark_square_hedit2 ends with a vertexedit (line 47) and an edgeedit (line 48) tag.
  const LoadedCage hedit = read_obj(corpus("catmark_square_hedit2"));
  ASSERT_EQ(hedit.diagnostics.size(), 2u);
  EXPECT_EQ(hedit.diagnostics[0].code, "unsupported-tag");
  EXPECT_NE(hedit.diagnostics[0].message.find("vertexedit"), std::string::npos);
  EXPECT_EQ(hedit.diagnostics[0].index, 47);  // the line
  EXPECT_NE(hedit.diagnostics[1].message.find("edgeedit"), std::string::npos);
  EXPECT_EQ(hedit.diagnostics[1].index, 48);
  EXPECT_NO_THROW(validate_cage(hedit));
}

TEST(CorpusReading, BareVerticesAreWarnings) {
  // catmark_nonman_bareverts: a grid with vertices that no face uses. Valid, with warnings.
  const LoadedCage cage = read_obj(corpus("catmark_nonman_bareverts"));
  Diagnostics diagnostics;
  validate_cage(cage, &diagnostics);
  ASSERT_FALSE(diagnostics.empty());
  for (const Diagnostic& d : diagnostics) {
    EXPECT_EQ(d.code, "unused-vertex");
    EXPECT_GT(source_line(cage, d), 0);
  }
}
