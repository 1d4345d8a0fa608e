// Every file in tests/data/invalid is rejected with the expected code at the expected line.
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <optional>
#include <set>

#include "io/obj_reader.h"

using namespace subd2nurbs;

namespace {

struct Expected {
  std::optional<MeshErrorCode> code;  ///< empty for OBJ syntax errors
  int line;                           ///< 0: the error is about the whole file
  const char* text;                   ///< a fragment of the message
};

/// File name -> expected error. Each file's first line says the same in words.
const std::map<std::string, Expected>& expectations() {
  static const std::map<std::string, Expected> table = {
      {"empty_mesh.obj", {MeshErrorCode::EmptyMesh, 0, "no mesh"}},
      {"nan_coordinate.obj", {MeshErrorCode::NonFiniteCoordinate, 4, "vertex 3 has a non-finite y"}},
      {"inf_coordinate.obj", {MeshErrorCode::NonFiniteCoordinate, 3, "vertex 2 has a non-finite z"}},
      {"face_two_vertices.obj", {MeshErrorCode::FaceTooSmall, 7, "2 vertices"}},
      {"index_out_of_range.obj", {MeshErrorCode::IndexOutOfRange, 8, "vertex 7"}},
      {"index_zero.obj", {MeshErrorCode::IndexOutOfRange, 6, "index 0"}},
      {"relative_index_out_of_range.obj", {MeshErrorCode::IndexOutOfRange, 7, "before the first"}},
      {"repeated_index.obj", {MeshErrorCode::RepeatedVertexInFace, 6, "vertex 2 twice"}},
      {"nonmanifold_edge.obj", {MeshErrorCode::NonManifoldEdge, 12, "lines 10, 11, 12"}},
      {"nonmanifold_vertex.obj", {MeshErrorCode::NonManifoldVertex, 5, "vertex 3 is non-manifold"}},
      {"inconsistent_orientation.obj", {MeshErrorCode::InconsistentOrientation, 10, "line 9"}},
      {"crease_not_an_edge.obj", {MeshErrorCode::InvalidTag, 9, "edge (0, 2)"}},
      {"crease_negative_sharpness.obj", {MeshErrorCode::InvalidTag, 12, "sharpness -1"}},
      {"corner_out_of_range.obj", {MeshErrorCode::InvalidTag, 7, "vertex 4"}},
      {"hole_out_of_range.obj", {MeshErrorCode::InvalidTag, 11, "face 2"}},
      {"malformed_tag.obj", {MeshErrorCode::InvalidTag, 7, "announces 3 arguments"}},
      {"malformed_tag_value.obj", {MeshErrorCode::InvalidTag, 7, "'linear'"}},
      {"bad_vertex.obj", {std::nullopt, 4, "3 coordinates"}},
      {"bad_face_token.obj", {std::nullopt, 6, "'x'"}},
  };
  return table;
}

std::string invalid_dir() { return std::string(SUBD2NURBS_TEST_DATA_DIR) + "/invalid"; }

/// Reads and validates; returns the error (fails the test if there is none).
std::optional<InputError> load_error(const std::string& path) {
  try {
    validate_cage(read_obj(path));
  } catch (const InputError& e) {
    return e;
  }
  return std::nullopt;
}

std::string code_name(std::optional<MeshErrorCode> c) { return c ? to_string(*c) : "(none)"; }

class InvalidFile : public ::testing::TestWithParam<std::string> {};

}  // namespace

TEST_P(InvalidFile, RejectedWithCodeAndLine) {
  const Expected& want = expectations().at(GetParam());
  const std::string path = invalid_dir() + "/" + GetParam();
  const std::optional<InputError> error = load_error(path);
  ASSERT_TRUE(error) << path << " was accepted";
  EXPECT_EQ(code_name(error->code()), code_name(want.code)) << error->what();
  EXPECT_EQ(error->line(), want.line) << error->what();
  EXPECT_EQ(error->file(), path);
  const std::string prefix = want.line > 0 ? path + ":" + std::to_string(want.line) + ": " : path + ": ";
  EXPECT_EQ(std::string(error->what()).rfind(prefix, 0), 0u) << error->what();
  EXPECT_NE(error->message().find(want.text), std::string::npos) << error->what();
}

INSTANTIATE_TEST_SUITE_P(Files, InvalidFile,
                         ::testing::ValuesIn([] {
                           std::vector<std::string> names;
                           for (const auto& [name, expected] : expectations()) names.push_back(name);
                           return names;
                         }()),
                         [](const ::testing::TestParamInfo<std::string>& p) {
                           return p.param.substr(0, p.param.size() - 4);  // without ".obj"
                         });

TEST(InvalidFiles, EveryFileInTheDirectoryHasAnExpectation) {
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(invalid_dir())) {
    if (entry.path().extension() != ".obj") continue;
    ++count;
    EXPECT_TRUE(expectations().count(entry.path().filename().string()))
        << entry.path() << " has no expected error";
  }
  EXPECT_EQ(count, static_cast<int>(expectations().size()));
}

TEST(InvalidFiles, EveryMeshErrorCodeIsCovered) {
  std::set<MeshErrorCode> covered;
  for (const auto& [name, expected] : expectations())
    if (expected.code) covered.insert(*expected.code);
  for (MeshErrorCode c : {MeshErrorCode::EmptyMesh, MeshErrorCode::NonFiniteCoordinate,
                          MeshErrorCode::FaceTooSmall, MeshErrorCode::IndexOutOfRange,
                          MeshErrorCode::RepeatedVertexInFace, MeshErrorCode::NonManifoldEdge,
                          MeshErrorCode::InconsistentOrientation, MeshErrorCode::NonManifoldVertex,
                          MeshErrorCode::InvalidTag})
    EXPECT_TRUE(covered.count(c)) << to_string(c);
}
