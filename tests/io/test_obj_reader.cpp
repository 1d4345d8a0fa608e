// read_obj on valid files: what is read, where it came from, and what is warned about.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>

#include "core/refine/refiner.h"
#include "io/obj_reader.h"
#include "io/temp_dir.h"

using namespace subd2nurbs;
using subd2nurbs::testing::TempDir;

namespace {

std::string valid(const std::string& name) {
  return std::string(SUBD2NURBS_TEST_DATA_DIR) + "/valid/" + name;
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

const Diagnostic* find_diagnostic(const Diagnostics& ds, const std::string& code, long index) {
  for (const Diagnostic& d : ds)
    if (d.code == code && d.index == index) return &d;
  return nullptr;
}

const std::string kQuad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";

}  // namespace

TEST(ObjReader, ReadsAllSupportedTags) {
  const LoadedCage cage = read_obj(valid("all_tags.obj"));
  const MeshInput& in = cage.input;
  ASSERT_EQ(in.num_vertices(), 12);
  ASSERT_EQ(in.num_faces(), 6);
  EXPECT_EQ(in.options.boundary, BoundaryRule::EdgeOnly);
  EXPECT_EQ(in.options.crease_method, CreaseMethod::Chaikin);
  EXPECT_EQ(in.options.triangles, TriangleRule::Smooth);

  // The chain 3-4-5 is two edges with their own sharpness, both from line 30.
  ASSERT_EQ(in.creases.size(), 2u);
  EXPECT_EQ(in.creases[0].v0, 3);
  EXPECT_EQ(in.creases[0].v1, 4);
  EXPECT_EQ(in.creases[0].sharpness, 1.5);
  EXPECT_EQ(in.creases[1].v0, 4);
  EXPECT_EQ(in.creases[1].v1, 5);
  EXPECT_EQ(in.creases[1].sharpness, 2.5);
  EXPECT_EQ(cage.crease_line, (std::vector<int>{30, 30}));

  ASSERT_EQ(in.corners.size(), 3u);
  EXPECT_EQ(in.corners[0].vertex, 0);
  EXPECT_EQ(in.corners[1].vertex, 2);
  EXPECT_EQ(in.corners[1].sharpness, 10.0);  // shared value
  EXPECT_EQ(in.corners[2].vertex, 10);
  EXPECT_EQ(in.corners[2].sharpness, 3.0);
  EXPECT_EQ(cage.corner_line, (std::vector<int>{32, 32, 33}));

  EXPECT_EQ(in.holes, (std::vector<int>{4, 5}));
  EXPECT_EQ(cage.hole_line, (std::vector<int>{34, 34}));
  EXPECT_TRUE(cage.diagnostics.empty());
}

TEST(ObjReader, RecordsLinesAndFaceLists) {
  const LoadedCage cage = read_obj(valid("all_tags.obj"));
  ASSERT_EQ(cage.vertex_line.size(), 12u);
  EXPECT_EQ(cage.vertex_line.front(), 8);
  EXPECT_EQ(cage.vertex_line.back(), 19);
  EXPECT_EQ(cage.face_line, (std::vector<int>{20, 21, 22, 23, 24, 25}));
  EXPECT_EQ(cage.input.face_sizes, (std::vector<int>(6, 4)));
  // "f 3 12 7 6" (third face) in 0-based indices.
  EXPECT_EQ(std::vector<int>(cage.input.face_indices.begin() + 8, cage.input.face_indices.begin() + 12),
            (std::vector<int>{2, 11, 6, 5}));
  EXPECT_EQ(cage.input.positions[11], (std::array<double, 3>{3, 0, 0}));
  EXPECT_EQ(cage.path, valid("all_tags.obj"));
}

TEST(ObjReader, DefaultOptionsWithoutTags) {
  TempDir dir;
  const LoadedCage cage = read_obj(dir.write("quad.obj", kQuad + "f 1 2 3 4\n"));
  EXPECT_EQ(cage.input.options.boundary, BoundaryRule::EdgeAndCorner);
  EXPECT_EQ(cage.input.options.crease_method, CreaseMethod::Uniform);
  EXPECT_EQ(cage.input.options.triangles, TriangleRule::Catmark);
}

TEST(ObjReader, InterpolateBoundaryValues) {
  TempDir dir;
  const BoundaryRule expected[] = {BoundaryRule::None, BoundaryRule::EdgeAndCorner,
                                   BoundaryRule::EdgeOnly};
  for (int value = 0; value < 3; ++value) {
    const std::string path = dir.write(
        "b.obj", kQuad + "f 1 2 3 4\nt interpolateboundary 1/0/0 " + std::to_string(value) + "\n");
    EXPECT_EQ(read_obj(path).input.options.boundary, expected[value]) << value;
  }
}

TEST(ObjReader, UnsupportedTagsAndStatementsAreWarningsWithLines) {
  const LoadedCage cage = read_obj(valid("unsupported_tags.obj"));
  EXPECT_EQ(cage.input.num_faces(), 1);
  EXPECT_EQ(cage.input.options.boundary, BoundaryRule::EdgeOnly);  // the tag after them
  // ElementKind::None diagnostics carry the line number as index.
  ASSERT_NE(find_diagnostic(cage.diagnostics, "unsupported-tag", 7), nullptr);
  ASSERT_NE(find_diagnostic(cage.diagnostics, "unsupported-tag", 8), nullptr);
  EXPECT_NE(find_diagnostic(cage.diagnostics, "unsupported-tag", 7)->message.find(
                "facevaryinginterpolateboundary"),
            std::string::npos);
  EXPECT_NE(find_diagnostic(cage.diagnostics, "ignored-element", 9), nullptr);
  EXPECT_NE(find_diagnostic(cage.diagnostics, "unknown-statement", 10), nullptr);
  // A repeated unknown statement is reported once.
  EXPECT_EQ(find_diagnostic(cage.diagnostics, "unknown-statement", 11), nullptr);
  EXPECT_EQ(cage.diagnostics.size(), 4u);
  for (const Diagnostic& d : cage.diagnostics) {
    EXPECT_EQ(d.element, ElementKind::None);
    EXPECT_EQ(source_line(cage, d), d.index);
  }
  EXPECT_EQ(format_diagnostic(cage, cage.diagnostics[0]).rfind(valid("unsupported_tags.obj") +
                                                                   ":7: warning: ",
                                                               0),
            0u);
}

TEST(ObjReader, UnusedVertexIsAWarningNotAnError) {
  const LoadedCage cage = read_obj(valid("unused_vertex.obj"));
  Diagnostics diagnostics;
  const SubdivLevel level = SubdivLevel::from_input(cage.input, &diagnostics);
  EXPECT_EQ(level.mesh.num_vertices(), 5);
  ASSERT_EQ(diagnostics.size(), 1u);
  EXPECT_EQ(diagnostics[0].code, "unused-vertex");
  EXPECT_EQ(diagnostics[0].element, ElementKind::Vertex);
  EXPECT_EQ(diagnostics[0].index, 4);
  EXPECT_EQ(source_line(cage, diagnostics[0]), 6);
  EXPECT_EQ(format_diagnostic(cage, diagnostics[0]),
            valid("unused_vertex.obj") + ":6: warning: vertex 5 is not used by any face");
}

TEST(ObjReader, ConcaveCornerIsAWarningNamingItsVertex) {
  // Two corners whose sectors the corner rule folds (core/mesh/corner_sectors.h): warnings that
  // name the OBJ's vertex numbers and lines (the exact limit's fold: tests/limit, ConcaveCorner).
  const LoadedCage cage = read_obj(valid("l_prism_concave.obj"));
  Diagnostics diagnostics;
  SubdivLevel::from_input(cage.input, &diagnostics);
  ASSERT_EQ(diagnostics.size(), 2u);
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(diagnostics[i].code, "concave-corner");
    EXPECT_EQ(diagnostics[i].index, 4 + 8 * i);
    const std::string vertex = std::to_string(5 + 8 * i);
    EXPECT_EQ(format_diagnostic(cage, diagnostics[i]).rfind(valid("l_prism_concave.obj") + ":" +
                                                                std::to_string(7 + 8 * i) + ": warning: vertex " +
                                                                vertex + " is a corner whose 3 faces between two "
                                                                "sharp edges span 270 degrees",
                                                            0),
              0u)
        << format_diagnostic(cage, diagnostics[i]);
  }
}

TEST(ObjReader, CoordinatesAreExactlyRounded) {
  // tinyobjloader's own parser returns -0.012886000000000002 for "-0.012886".
  const char* texts[] = {"-0.012886", "0.10000000000000001", "123456.78901234567",
                         "1.2345678901234567e-5", "+2.5", "-0", "4.9406564584124654e-324"};
  std::string obj;
  for (const char* t : texts) obj += std::string("v ") + t + " 0 0\n";
  obj += "f 1 2 3\n";
  TempDir dir;
  const LoadedCage cage = read_obj(dir.write("exact.obj", obj));
  ASSERT_EQ(cage.input.num_vertices(), 7);
  for (int i = 0; i < 7; ++i)
    EXPECT_TRUE(same_bits(cage.input.positions[i][0], std::strtod(texts[i], nullptr))) << texts[i];
}

TEST(ObjReader, NonFiniteAndOutOfRangeCoordinatesReachValidation) {
  TempDir dir;
  const LoadedCage cage = read_obj(
      dir.write("nf.obj", "v nan 0 0\nv 0 inf 0\nv 0 0 -INF\nv 1e999 0 0\nv 1e-400 0 0\nf 1 2 3\n"));
  const auto& p = cage.input.positions;
  EXPECT_TRUE(std::isnan(p[0][0]));
  EXPECT_EQ(p[1][1], INFINITY);
  EXPECT_EQ(p[2][2], -INFINITY);
  EXPECT_EQ(p[3][0], INFINITY);  // overflow saturates, as strtod does
  EXPECT_EQ(p[4][0], 0.0);       // underflow
}

TEST(ObjReader, FaceFormsNegativeIndicesAndExtraVertexValues) {
  TempDir dir;
  const std::string obj =
      "v 0 0 0 1\n"            // w is ignored
      "v 1 0 0 0.5 0.5 0.5\n"  // so are colours
      "v 1 1 0\n"
      "v 0 1 0\n"
      "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
      "vn 0 0 1\n"
      "f 1/1/1 2/2/1 3/3/1 4/4/1\n"
      "v 2 0 0\nv 2 1 0\n"
      "f -5//1 -2//1 -1//1 -4//1\n"  // 2 5 6 3
      "f 5/1 -1/2 3/3\n";            // 5 6 3
  const LoadedCage cage = read_obj(dir.write("forms.obj", obj));
  EXPECT_EQ(cage.input.face_sizes, (std::vector<int>{4, 4, 3}));
  EXPECT_EQ(cage.input.face_indices, (std::vector<int>{0, 1, 2, 3, 1, 4, 5, 2, 4, 5, 2}));
  EXPECT_EQ(cage.input.positions[1], (std::array<double, 3>{1, 0, 0}));
  EXPECT_EQ(cage.vertex_line, (std::vector<int>{1, 2, 3, 4, 11, 12}));
  EXPECT_EQ(cage.face_line, (std::vector<int>{10, 13, 14}));
}

TEST(ObjReader, FacesOfAllGroupsInFileOrder) {
  TempDir dir;
  const std::string obj = kQuad +
                          "v 2 0 0\nv 2 1 0\n"
                          "mtllib missing.mtl\n"
                          "f 1 2 3\n"
                          "g a\nusemtl red\nf 1 3 4\n"
                          "o thing\ns 1\nusemtl blue\nf 2 5 6 3\n"
                          "g a\nf 3 6 4\n";
  const LoadedCage cage = read_obj(dir.write("groups.obj", obj));
  EXPECT_EQ(cage.input.face_sizes, (std::vector<int>{3, 3, 4, 3}));
  EXPECT_EQ(cage.input.face_indices,
            (std::vector<int>{0, 1, 2, 0, 2, 3, 1, 4, 5, 2, 2, 5, 3}));
  EXPECT_TRUE(cage.diagnostics.empty());  // groups, materials, smoothing: silently ignored
}

TEST(ObjReader, WindowsAndOldMacLineEndings) {
  TempDir dir;
  const LoadedCage crlf =
      read_obj(dir.write("crlf.obj", "# c\r\nv 0 0 0\r\nv 1 0 0\r\nv 1 1 0\r\n\r\nf 1 2 3\r\n"));
  EXPECT_EQ(crlf.face_line, (std::vector<int>{6}));
  EXPECT_EQ(crlf.input.face_indices, (std::vector<int>{0, 1, 2}));
  const LoadedCage cr = read_obj(dir.write("cr.obj", "v 0 0 0\rv 1 0 0\rv 1 1 0\rf 1 2 3"));
  EXPECT_EQ(cr.vertex_line, (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(cr.face_line, (std::vector<int>{4}));
}

TEST(ObjReader, FaceWithMoreThan255Vertices) {
  // tinyobjloader stores face sizes as unsigned char; the reader must not truncate.
  const int n = 300;
  std::string obj, face = "f";
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * i / n;
    obj += "v " + std::to_string(std::cos(a)) + " " + std::to_string(std::sin(a)) + " 0\n";
    face += " " + std::to_string(i + 1);
  }
  TempDir dir;
  const LoadedCage cage = read_obj(dir.write("ngon.obj", obj + face + "\n"));
  ASSERT_EQ(cage.input.face_sizes, (std::vector<int>{n}));
  for (int i = 0; i < n; ++i) ASSERT_EQ(cage.input.face_indices[i], i);
  EXPECT_EQ(SubdivLevel::from_input(cage.input).mesh.num_edges(), n);
}

TEST(ObjReader, MalformedFaceCornersNameTheirLine) {
  TempDir dir;
  const std::string header = kQuad + "vt 0 0\nvn 0 0 1\n";  // lines 1-6
  for (const char* corner : {"1/1/1/1", "1/0", "1//0", "1/x/1", "1/", "x//1", "+"}) {
    try {
      read_obj(dir.write("bad.obj", header + "f 2 3 4\nf 2 " + std::string(corner) + " 4\n"));
      ADD_FAILURE() << corner << " was accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.line(), 8) << corner << ": " << e.what();
      EXPECT_FALSE(e.code().has_value()) << corner << ": " << e.what();
    }
  }
  // Accepted forms, including a leading '+', which tinyobjloader reads as well.
  const LoadedCage ok = read_obj(dir.write("ok.obj", header + "f 1/1 2//1 3/1/1 +4\n"));
  EXPECT_EQ(ok.input.face_indices, (std::vector<int>{0, 1, 2, 3}));
}

TEST(ObjReader, MissingFileIsAnInputErrorWithoutLine) {
  TempDir dir;
  const std::string path = dir.file("absent.obj");
  try {
    read_obj(path);
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(e.line(), 0);
    EXPECT_FALSE(e.code().has_value());
    EXPECT_EQ(std::string(e.what()), path + ": no such file");
  }
}

TEST(ObjReader, DirectoryIsAnInputError) {
  TempDir dir;
  EXPECT_THROW(read_obj(dir.path().string()), InputError);
}

TEST(InputErrorText, FormatsFileAndLine) {
  EXPECT_STREQ(InputError("a.obj", 12, "bad").what(), "a.obj:12: bad");
  EXPECT_STREQ(InputError("a.obj", 0, "bad").what(), "a.obj: bad");
  EXPECT_STREQ(WriteError("b.obj", "full").what(), "b.obj: full");
}
