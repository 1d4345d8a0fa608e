// The glTF / GLB cage reader (io/gltf_reader.h). Oracle: corpus cages we write ourselves as
// glTF triangles (tests/common/gltf_writer.h), the way exporters do (split vertices at seams,
// a node transform): reading them back must give the cage's own faces, as quads.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "common/gltf_writer.h"
#include "io/cage_reader.h"
#include "io/gltf_reader.h"
#include "io/input_error.h"

namespace subd2nurbs {
namespace {

namespace fs = std::filesystem;

class Gltf : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("subd2nurbs_gltf_" + std::to_string(::getpid()) + "_" + std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

/// Faces of `read` in terms of `original`'s vertices (matched by position, minus `shift`),
/// each rotated to start at its smallest vertex.
std::multiset<std::vector<int>> faces_in(const MeshInput& read, const MeshInput& original,
                                         const std::array<double, 3>& shift) {
  std::vector<int> match(read.positions.size(), -1);
  double size = 0;
  for (const auto& p : original.positions) size = std::max({size, std::abs(p[0]), std::abs(p[1]), std::abs(p[2])});
  for (size_t i = 0; i < read.positions.size(); ++i) {
    double best = 1e300;
    for (size_t j = 0; j < original.positions.size(); ++j) {
      double d = 0;
      for (int k = 0; k < 3; ++k) d = std::max(d, std::abs(read.positions[i][k] - shift[k] - original.positions[j][k]));
      if (d < best) {
        best = d;
        match[i] = static_cast<int>(j);
      }
    }
    EXPECT_LT(best, 1e-6 * (1 + size)) << "vertex " << i;  // float32 storage
  }
  std::multiset<std::vector<int>> faces;
  size_t o = 0;
  for (int n : read.face_sizes) {
    std::vector<int> f;
    for (int k = 0; k < n; ++k) f.push_back(match[static_cast<size_t>(read.face_indices[o + k])]);
    o += static_cast<size_t>(n);
    std::rotate(f.begin(), std::min_element(f.begin(), f.end()), f.end());
    faces.insert(f);
  }
  return faces;
}

std::multiset<std::vector<int>> faces_of(const MeshInput& m) { return faces_in(m, m, {0, 0, 0}); }

TEST_F(Gltf, CorpusQuadCagesComeBackAsTheirQuads) {
  for (const std::string name : {"catmark_cube", "catmark_torus", "catmark_helmet", "catmark_cubes_infsharp", "catmark_flap"}) {
    const LoadedCage obj = read_obj(std::string(SUBD2NURBS_CORPUS_DIR) + "/" + name + ".obj");
    for (bool split : {false, true}) {
      for (bool binary : {true, false}) {
        SCOPED_TRACE(name + (split ? " split" : "") + (binary ? " glb" : " gltf"));
        testing::GltfOptions o;
        o.split_vertices = split;
        o.binary = binary;
        o.second_diagonal = split;
        o.translation = {1.5, -2, 0.25};
        const std::string file = path(name + (binary ? ".glb" : ".gltf"));
        testing::write_gltf(obj.input, file, o);
        const LoadedCage cage = read_cage(file);
        EXPECT_TRUE(cage.recovery.applied);
        EXPECT_EQ(cage.recovery.source_triangles, 2 * obj.input.num_faces());
        EXPECT_EQ(cage.recovery.quads, obj.input.num_faces());
        EXPECT_EQ(cage.recovery.triangles_kept, 0);
        EXPECT_EQ(cage.input.num_vertices(), obj.input.num_vertices());  // welded
        EXPECT_EQ(faces_in(cage.input, obj.input, o.translation), faces_of(obj.input));
        EXPECT_NO_THROW(validate_cage(cage));
      }
    }
  }
}

TEST_F(Gltf, PoleFansStayTriangles) {
  // catmark_pole8 has triangles around its poles (and quads elsewhere).
  const LoadedCage obj = read_obj(std::string(SUBD2NURBS_CORPUS_DIR) + "/catmark_pole8.obj");
  int obj_triangles = 0, obj_quads = 0;
  for (int n : obj.input.face_sizes) (n == 3 ? obj_triangles : obj_quads) += 1;
  ASSERT_GT(obj_triangles, 0);
  testing::write_gltf(obj.input, path("pole8.glb"));
  const LoadedCage cage = read_gltf(path("pole8.glb"));
  EXPECT_EQ(cage.recovery.quads, obj_quads);
  EXPECT_EQ(cage.recovery.triangles_kept, obj_triangles);
  EXPECT_EQ(faces_of(cage.input), faces_of(obj.input));
}

TEST_F(Gltf, BadFilesNameTheFile) {
  EXPECT_THROW(read_gltf(path("missing.glb")), InputError);
  {
    std::ofstream(path("junk.glb")) << "not a glb";
    std::ofstream(path("junk.gltf")) << "{ not json";
  }
  for (const std::string name : {"junk.glb", "junk.gltf"}) {
    try {
      read_cage(path(name));
      ADD_FAILURE() << name << " was accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), path(name));
      EXPECT_NE(std::string(e.what()).find(path(name)), std::string::npos);
    }
  }
  // A scene without triangles.
  {
    std::ofstream(path("empty.gltf")) << R"({"asset": {"version": "2.0"}, "scenes": [{"nodes": []}], "scene": 0})";
  }
  try {
    read_gltf(path("empty.gltf"));
    ADD_FAILURE() << "an empty scene was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no triangles"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace subd2nurbs
