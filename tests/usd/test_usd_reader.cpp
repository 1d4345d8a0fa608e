// The USD reader (io/usd_reader.h) against independent oracles:
//  * the same cage written by the test as OBJ with OpenSubdiv tags, as usda text and as a usdc
//    crate (tests/usd/crate_writer.h, the test's own writer) reads to identical MeshInputs and
//    identical patches;
//  * a crease read from USD refines as OpenSubdiv refines the same tags (tests/oracle), and
//    changes the surface;
//  * transforms: points under translate / rotate / scale / orient / transform / !invert!
//    against the same points moved by hand (formulas written out here), leftHanded and
//    mirrored meshes with their faces reversed;
//  * hostile input: truncated crates, counts beyond the bytes, out-of-range indices, cyclic
//    paths and references, absurd nesting give InputError naming the file and the problem.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "core/patch/patch_builder.h"
#include "core/refine/refiner.h"
#include "io/cage_reader.h"
#include "io/input_error.h"
#include "io/obj_reader.h"
#include "io/usd_reader.h"
#include "oracle/osd_reference.h"
#include "usd/crate_writer.h"

namespace subd2nurbs {
namespace {

using testing::CrateWriter;

// The test cage: a 2 x 1 x 1 box split into two cubes (12 vertices, 10 quads... as 11 faces
// with one triangle fan? no: plain quads), with a crease chain, a corner, a hole.
struct Cage {
  std::vector<std::array<float, 3>> points;
  std::vector<int> counts, indices;
  std::vector<int> crease = {0, 1, 2};  // a chain of two edges along the bottom front
  float crease_sharpness = 2.5f;
  std::vector<int> corners = {11};
  float corner_sharpness = 10;
  int hole = 3;
};

Cage box() {
  Cage c;
  // Vertices: x in {0, 1, 2}, y in {0, 1}, z in {0, 1}: index = x + 3 * (y + 2 * z).
  for (int z = 0; z < 2; ++z)
    for (int y = 0; y < 2; ++y)
      for (int x = 0; x < 3; ++x) c.points.push_back({float(x), float(y), float(z)});
  auto v = [](int x, int y, int z) { return x + 3 * (y + 2 * z); };
  auto quad = [&](int a, int b, int cc, int d) {
    c.counts.push_back(4);
    c.indices.insert(c.indices.end(), {a, b, cc, d});
  };
  for (int x = 0; x < 2; ++x) {
    quad(v(x, 0, 0), v(x, 1, 0), v(x + 1, 1, 0), v(x + 1, 0, 0));  // bottom (z = 0), normal -z
    quad(v(x, 0, 1), v(x + 1, 0, 1), v(x + 1, 1, 1), v(x, 1, 1));  // top, +z
    quad(v(x, 0, 0), v(x + 1, 0, 0), v(x + 1, 0, 1), v(x, 0, 1));  // front (y = 0), -y
    quad(v(x, 1, 0), v(x, 1, 1), v(x + 1, 1, 1), v(x + 1, 1, 0));  // back, +y
  }
  quad(v(0, 0, 0), v(0, 0, 1), v(0, 1, 1), v(0, 1, 0));  // left, -x
  quad(v(2, 0, 0), v(2, 1, 0), v(2, 1, 1), v(2, 0, 1));  // right, +x
  return c;
}

std::string as_obj(const Cage& c) {
  std::string s;
  for (const auto& p : c.points) s += "v " + std::to_string(p[0]) + " " + std::to_string(p[1]) + " " + std::to_string(p[2]) + "\n";
  std::size_t at = 0;
  for (int n : c.counts) {
    s += "f";
    for (int k = 0; k < n; ++k) s += " " + std::to_string(c.indices[at++] + 1);
    s += "\n";
  }
  s += "t crease 3/1/0 0 1 2 2.5\n";
  s += "t corner 1/1/0 11 10\n";
  s += "t hole 1/0/0 3\n";
  s += "t interpolateboundary 1/0/0 2\n";
  s += "t smoothtriangles 0/0/1 smooth\n";
  return s;
}

template <class T>
std::string list(const std::vector<T>& v) {
  std::string s = "[";
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + std::to_string(v[i]);
  return s + "]";
}

std::string points_text(const std::vector<std::array<float, 3>>& points) {
  std::string s = "[";
  for (std::size_t i = 0; i < points.size(); ++i)
    s += (i ? ", (" : "(") + std::to_string(points[i][0]) + ", " + std::to_string(points[i][1]) + ", " +
         std::to_string(points[i][2]) + ")";
  return s + "]";
}

std::string as_usda(const Cage& c) {
  return "#usda 1.0\n(\n    defaultPrim = \"Box\"\n    metersPerUnit = 0.001\n    upAxis = \"Z\"\n)\n\n"
         "def Xform \"Box\"\n{\n    def Mesh \"shape\"\n    {\n"
         "        int[] faceVertexCounts = " + list(c.counts) + "\n"
         "        int[] faceVertexIndices = " + list(c.indices) + "\n"
         "        point3f[] points = " + points_text(c.points) + " (\n            interpolation = \"vertex\"\n        )\n"
         "        int[] creaseIndices = " + list(c.crease) + "\n"
         "        int[] creaseLengths = [3]\n"
         "        float[] creaseSharpnesses = [2.5]\n"
         "        int[] cornerIndices = " + list(c.corners) + "\n"
         "        float[] cornerSharpnesses = [10]\n"
         "        int[] holeIndices = [" + std::to_string(c.hole) + "]\n"
         "        uniform token interpolateBoundary = \"edgeOnly\"\n"
         "        uniform token triangleSubdivisionRule = \"smooth\"\n"
         "        uniform token subdivisionScheme = \"catmullClark\"\n"
         "        # a comment\n"
         "        rel material:binding = </Materials/red>\n"
         "        def GeomSubset \"part\" { int[] indices = [0, 1] }\n"
         "    }\n}\n";
}

/// The cage as a crate: /Box (Xform) / shape (Mesh), faceVertexIndices compressed.
std::string as_usdc(const Cage& c, bool compress = true) {
  CrateWriter w;
  const int box = w.path(0, "Box");
  const int shape = w.path(box, "shape");
  w.spec(0, CrateWriter::kPseudoRoot, {{"metersPerUnit", w.double_value(0.001)}, {"upAxis", w.token_value("Z")},
                                       {"primChildren", w.token_vector({"Box"})}});
  w.spec(box, CrateWriter::kPrim, {{"specifier", w.specifier(0)}, {"typeName", w.token_value("Xform")},
                                   {"primChildren", w.token_vector({"shape"})}});
  w.spec(shape, CrateWriter::kPrim, {{"specifier", w.specifier(0)}, {"typeName", w.token_value("Mesh")}});
  auto attribute = [&](const std::string& name, const std::string& type, std::uint64_t value) {
    w.spec(w.path(shape, name, true), CrateWriter::kAttribute, {{"typeName", w.token_value(type)}, {"default", value}});
  };
  attribute("faceVertexCounts", "int[]", w.int_array(c.counts, compress));
  attribute("faceVertexIndices", "int[]", w.int_array(c.indices, compress));
  attribute("points", "point3f[]", w.vec3f_array(c.points));
  attribute("creaseIndices", "int[]", w.int_array(c.crease, compress));
  attribute("creaseLengths", "int[]", w.int_array({3}, compress));
  attribute("creaseSharpnesses", "float[]", w.float_array({c.crease_sharpness}));
  attribute("cornerIndices", "int[]", w.int_array(c.corners, compress));
  attribute("cornerSharpnesses", "float[]", w.float_array({c.corner_sharpness}));
  attribute("holeIndices", "int[]", w.int_array({c.hole}, compress));
  attribute("interpolateBoundary", "token", w.token_value("edgeOnly"));
  attribute("triangleSubdivisionRule", "token", w.token_value("smooth"));
  return w.finish();
}

void expect_same_input(const MeshInput& a, const MeshInput& b) {
  ASSERT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.face_sizes, b.face_sizes);
  EXPECT_EQ(a.face_indices, b.face_indices);
  ASSERT_EQ(a.creases.size(), b.creases.size());
  for (std::size_t i = 0; i < a.creases.size(); ++i) {
    EXPECT_EQ(a.creases[i].v0, b.creases[i].v0);
    EXPECT_EQ(a.creases[i].v1, b.creases[i].v1);
    EXPECT_EQ(a.creases[i].sharpness, b.creases[i].sharpness);
  }
  ASSERT_EQ(a.corners.size(), b.corners.size());
  for (std::size_t i = 0; i < a.corners.size(); ++i) {
    EXPECT_EQ(a.corners[i].vertex, b.corners[i].vertex);
    EXPECT_EQ(a.corners[i].sharpness, b.corners[i].sharpness);
  }
  EXPECT_EQ(a.holes, b.holes);
  EXPECT_EQ(a.options.boundary, b.options.boundary);
  EXPECT_EQ(a.options.crease_method, b.options.crease_method);
  EXPECT_EQ(a.options.triangles, b.options.triangles);
}

PatchSet patches_of(const LoadedCage& cage) {
  const SubdivLevel base = SubdivLevel::from_validated(validate_cage(cage), cage.input);
  std::vector<Point3> positions(cage.input.positions.begin(), cage.input.positions.end());
  return build_patches(base, positions).set;
}

TEST(UsdReader, ObjUsdaUsdcReadToTheSameCageAndPatches) {
  const Cage c = box();
  const LoadedCage obj = parse_obj(as_obj(c), "box.obj");
  const LoadedCage usda = parse_usd(as_usda(c), "box.usda");
  const LoadedCage usdc = parse_usd(as_usdc(c), "box.usdc");
  const LoadedCage usdc_raw = parse_usd(as_usdc(c, false), "box_raw.usdc");
  // The OBJ's tags as written: the chain gives 2 creases, 1 corner, 1 hole, edge-only, smooth.
  ASSERT_EQ(obj.input.creases.size(), 2u);
  ASSERT_EQ(obj.input.options.boundary, BoundaryRule::EdgeOnly);
  expect_same_input(obj.input, usda.input);
  expect_same_input(obj.input, usdc.input);
  expect_same_input(obj.input, usdc_raw.input);
  EXPECT_EQ(usda.usd.encoding, "usda");
  EXPECT_EQ(usdc.usd.encoding, "usdc");
  EXPECT_EQ(usdc.usd.version, "0.8.0");
  for (const LoadedCage* u : {&usda, &usdc}) {
    EXPECT_EQ(u->usd.meters_per_unit, 0.001);
    EXPECT_EQ(u->usd.up_axis, "Z");
    ASSERT_EQ(u->usd.meshes.size(), 1u);
    EXPECT_EQ(u->usd.meshes[0].path, "/Box/shape");
    EXPECT_EQ(u->usd.meshes[0].creases, 2);
    EXPECT_EQ(u->usd.meshes[0].corners, 1);
    EXPECT_EQ(u->usd.meshes[0].holes, 1);
  }
  const PatchSet a = patches_of(obj), b = patches_of(usda), d = patches_of(usdc);
  ASSERT_EQ(a.patches.size(), b.patches.size());
  ASSERT_EQ(a.patches.size(), d.patches.size());
  ASSERT_GT(a.patches.size(), 0u);
  for (std::size_t i = 0; i < a.patches.size(); ++i) {
    EXPECT_EQ(a.patches[i].poles, b.patches[i].poles) << "patch " << i;
    EXPECT_EQ(a.patches[i].poles, d.patches[i].poles) << "patch " << i;
    EXPECT_EQ(a.patches[i].num_poles_u, d.patches[i].num_poles_u) << "patch " << i;
  }
}

TEST(UsdReader, CrateIntegerCodingRoundTripsEveryDeltaSize) {
  // Deltas of every code: common, 8-bit, 16-bit, 32-bit, negative, as a points-free probe:
  // faceVertexIndices is checked against the mesh's point count, so use creaseIndices-free
  // counts instead: a fan of triangles around vertex 0 with indices far apart.
  Cage c;
  const int n = 40;
  for (int i = 0; i <= n; ++i) c.points.push_back({float(i), float(i * i % 7), 0});
  // Indices in an order whose deltas are big and small: 0, i, i+1 with i visiting in a scrambled way.
  for (int k = 0; k < n - 1; ++k) {
    const int i = 1 + (k * 17) % (n - 1);
    c.counts.push_back(3);
    c.indices.insert(c.indices.end(), {0, i, i + 1});
  }
  CrateWriter w;
  const int m = w.path(0, "m");
  w.spec(0, CrateWriter::kPseudoRoot, {});
  w.spec(m, CrateWriter::kPrim, {{"specifier", w.specifier(0)}, {"typeName", w.token_value("Mesh")}});
  w.spec(w.path(m, "faceVertexCounts", true), CrateWriter::kAttribute, {{"default", w.int_array(c.counts, true)}});
  w.spec(w.path(m, "faceVertexIndices", true), CrateWriter::kAttribute, {{"default", w.int_array(c.indices, true)}});
  w.spec(w.path(m, "points", true), CrateWriter::kAttribute, {{"default", w.vec3f_array(c.points)}});
  const LoadedCage cage = parse_usd(w.finish(), "fan.usdc");
  EXPECT_EQ(cage.input.face_indices, c.indices);
  // And the coder itself over 8/16/32-bit deltas, through a crease index list read back.
  const std::vector<int> big = {0, 5, -3, 300, -40000, 2000000000, -2000000000, 7, 7, 7, 7, 7, 7, 7, 7, 7, 1, 2};
  CrateWriter w2;
  const int m2 = w2.path(0, "m");
  w2.spec(0, CrateWriter::kPseudoRoot, {});
  w2.spec(m2, CrateWriter::kPrim, {{"specifier", w2.specifier(0)}, {"typeName", w2.token_value("Mesh")}});
  w2.spec(w2.path(m2, "faceVertexCounts", true), CrateWriter::kAttribute, {{"default", w2.int_array({3}, false)}});
  w2.spec(w2.path(m2, "faceVertexIndices", true), CrateWriter::kAttribute, {{"default", w2.int_array({0, 1, 2}, false)}});
  w2.spec(w2.path(m2, "points", true), CrateWriter::kAttribute,
          {{"default", w2.vec3f_array({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}})}});
  w2.spec(w2.path(m2, "holeIndices", true), CrateWriter::kAttribute, {{"default", w2.int_array(big, true)}});
  try {
    parse_usd(w2.finish(), "big.usdc");
    FAIL() << "hole 5 of a 1-face mesh accepted";
  } catch (const InputError& e) {
    // The first index is 0 (valid), the second 5: the message names it, so the decoding is right.
    EXPECT_NE(std::string(e.what()).find("holeIndices names face 5"), std::string::npos) << e.what();
  }
}

// --- OpenSubdiv agrees on the crease read from USD --------------------------------------------

TEST(UsdReader, CreaseFromUsdRefinesAsOpenSubdivWithTheSameTags) {
  const Cage c = box();
  std::string text = as_usda(c);
  const LoadedCage usda = parse_usd(text, "box.usda");
  MeshInput input = usda.input;
  input.holes.clear();  // the oracle's comparison covers holes too, but keep it to the crease
  const testing::OsdComparison cmp = testing::compare_with_osd(input, 3);
  ASSERT_TRUE(cmp.osd_accepted);
  EXPECT_EQ(cmp.sharpness_mismatches, 0) << cmp.first_problem;
  EXPECT_EQ(cmp.face_mismatches, 0) << cmp.first_problem;
  EXPECT_LE(cmp.max_relative_error, 1e-12) << cmp.first_problem;
  // The crease matters: without it OpenSubdiv's refinement differs at the crease vertices.
  MeshInput smooth = input;
  smooth.creases.clear();
  const testing::OsdRefinement with = testing::osd_refine(input, 2), without = testing::osd_refine(smooth, 2);
  double moved = 0;
  for (std::size_t i = 0; i < with.positions[2].size(); ++i)
    for (int k = 0; k < 3; ++k) moved = std::max(moved, std::abs(with.positions[2][i][k] - without.positions[2][i][k]));
  EXPECT_GT(moved, 1e-3);
}

// --- transforms -------------------------------------------------------------------------------

std::string mesh_with_ops(const std::string& parent_ops, const std::string& mesh_ops, const std::string& extra = "") {
  return "#usda 1.0\ndef Xform \"A\"\n{\n" + parent_ops +
         "    def Mesh \"m\"\n    {\n" + mesh_ops + extra +
         "        int[] faceVertexCounts = [4]\n        int[] faceVertexIndices = [0, 1, 2, 3]\n"
         "        point3f[] points = [(1, 0, 0), (2, 0.5, 0), (2, 1, 3), (1, 1, 0.25)]\n    }\n}\n";
}

const std::vector<std::array<double, 3>> kQuad = {{1, 0, 0}, {2, 0.5, 0}, {2, 1, 3}, {1, 1, 0.25}};

void expect_points(const LoadedCage& cage, const std::vector<std::array<double, 3>>& expected) {
  ASSERT_EQ(cage.input.positions.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i)
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(cage.input.positions[i][k], expected[i][k], 1e-12) << "point " << i << " axis " << k;
}

TEST(UsdReader, TransformsComposeDownTheHierarchy) {
  // Parent: translate (1, 2, 3). Mesh: rotateZ 90 after scale (2, 1, 1) (xformOpOrder lists the
  // outermost first): p -> (2x, y, z) -> (-y, 2x, z) -> (-y + 1, 2x + 2, z + 3).
  const LoadedCage cage = parse_usd(
      mesh_with_ops("    double3 xformOp:translate = (1, 2, 3)\n    uniform token[] xformOpOrder = [\"xformOp:translate\"]\n",
                    "        float xformOp:rotateZ = 90\n        double3 xformOp:scale = (2, 1, 1)\n"
                    "        uniform token[] xformOpOrder = [\"xformOp:rotateZ\", \"xformOp:scale\"]\n"),
      "t.usda");
  std::vector<std::array<double, 3>> expected;
  for (const auto& p : kQuad) expected.push_back({-p[1] + 1, 2 * p[0] + 2, p[2] + 3});
  expect_points(cage, expected);
  EXPECT_EQ(cage.input.face_indices, (std::vector<int>{0, 1, 2, 3}));
}

TEST(UsdReader, RotateXyzOrientTransformInvertAndReset) {
  // rotateXYZ (90, 0, 90): X first, then Z: (x, y, z) -> (x, -z, y) -> (z, x, y).
  {
    const LoadedCage cage = parse_usd(
        mesh_with_ops("", "        float3 xformOp:rotateXYZ = (90, 0, 90)\n        uniform token[] xformOpOrder = [\"xformOp:rotateXYZ\"]\n"),
        "r.usda");
    std::vector<std::array<double, 3>> expected;
    for (const auto& p : kQuad) expected.push_back({p[2], p[0], p[1]});
    expect_points(cage, expected);
  }
  // orient: the quaternion (cos 45, 0, 0, sin 45) is rotateZ 90: (x, y, z) -> (-y, x, z).
  {
    const LoadedCage cage = parse_usd(
        mesh_with_ops("", "        quatf xformOp:orient = (0.70710678118654752, 0, 0, 0.70710678118654752)\n"
                          "        uniform token[] xformOpOrder = [\"xformOp:orient\"]\n"),
        "o.usda");
    std::vector<std::array<double, 3>> expected;
    for (const auto& p : kQuad) expected.push_back({-p[1], p[0], p[2]});
    ASSERT_EQ(cage.input.positions.size(), 4u);
    for (std::size_t i = 0; i < 4; ++i)
      for (int k = 0; k < 3; ++k) EXPECT_NEAR(cage.input.positions[i][k], expected[i][k], 1e-7);
  }
  // transform: USD's row-vector matrix, p' = p M: x' = -y + 5, y' = x + 6, z' = z + 7; under a
  // parent whose !resetXformStack! makes the parent's translate not apply.
  {
    const LoadedCage cage = parse_usd(
        mesh_with_ops("    double3 xformOp:translate = (100, 100, 100)\n    uniform token[] xformOpOrder = [\"xformOp:translate\"]\n",
                      "        matrix4d xformOp:transform = ( (0, 1, 0, 0), (-1, 0, 0, 0), (0, 0, 1, 0), (5, 6, 7, 1) )\n"
                      "        uniform token[] xformOpOrder = [\"!resetXformStack!\", \"xformOp:transform\"]\n"),
        "m.usda");
    std::vector<std::array<double, 3>> expected;
    for (const auto& p : kQuad) expected.push_back({-p[1] + 5, p[0] + 6, p[2] + 7});
    expect_points(cage, expected);
  }
  // A pivot: translate:pivot, scale, !invert!translate:pivot scales about the pivot (1, 1, 1).
  {
    const LoadedCage cage = parse_usd(
        mesh_with_ops("", "        double3 xformOp:translate:pivot = (1, 1, 1)\n        float3 xformOp:scale = (3, 3, 3)\n"
                          "        uniform token[] xformOpOrder = [\"xformOp:translate:pivot\", \"xformOp:scale\", "
                          "\"!invert!xformOp:translate:pivot\"]\n"),
        "p.usda");
    std::vector<std::array<double, 3>> expected;
    for (const auto& p : kQuad) expected.push_back({3 * (p[0] - 1) + 1, 3 * (p[1] - 1) + 1, 3 * (p[2] - 1) + 1});
    expect_points(cage, expected);
  }
}

TEST(UsdReader, LeftHandedAndMirroredMeshesHaveTheirFacesReversed) {
  const LoadedCage left = parse_usd(mesh_with_ops("", "        uniform token orientation = \"leftHanded\"\n"), "l.usda");
  EXPECT_EQ(left.input.face_indices, (std::vector<int>{0, 3, 2, 1}));
  const LoadedCage mirrored = parse_usd(
      mesh_with_ops("", "        double3 xformOp:scale = (-1, 1, 1)\n        uniform token[] xformOpOrder = [\"xformOp:scale\"]\n"),
      "s.usda");
  EXPECT_EQ(mirrored.input.face_indices, (std::vector<int>{0, 3, 2, 1}));
  const LoadedCage both = parse_usd(
      mesh_with_ops("", "        double3 xformOp:scale = (-1, 1, 1)\n        uniform token[] xformOpOrder = [\"xformOp:scale\"]\n"
                        "        uniform token orientation = \"leftHanded\"\n"),
      "b.usda");
  EXPECT_EQ(both.input.face_indices, (std::vector<int>{0, 1, 2, 3}));
}

TEST(UsdReader, TimeSamplesVariantsReferencesAndSeveralMeshes) {
  const std::string text =
      "#usda 1.0\n"
      "over \"src\" (hidden = true)\n{\n  def Mesh \"m\"\n  {\n"
      "    int[] faceVertexCounts = [3]\n    int[] faceVertexIndices = [0, 1, 2]\n"
      "    point3f[] points.timeSamples = { 2: [(0, 0, 2), (1, 0, 2), (0, 1, 2)], 1: [(0, 0, 1), (1, 0, 1), (0, 1, 1)], }\n"
      "  }\n}\n"
      "def Xform \"root\" (\n  variants = { string look = \"b\" }\n  prepend variantSets = \"look\"\n)\n{\n"
      "  variantSet \"look\" = {\n"
      "    \"a\" { def Mesh \"va\" { int[] faceVertexCounts = [3]\n int[] faceVertexIndices = [0, 1, 2]\n"
      "          point3f[] points = [(5, 0, 0), (6, 0, 0), (5, 1, 0)] } }\n"
      "    \"b\" { def Mesh \"vb\" { int[] faceVertexCounts = [3]\n int[] faceVertexIndices = [0, 2, 1]\n"
      "          point3f[] points = [(7, 0, 0), (8, 0, 0), (7, 1, 0)] } }\n"
      "  }\n"
      "  def \"ref\" ( prepend references = </src> ) {}\n"
      "}\n"
      "def Xform \"hidden\" { token visibility = \"invisible\"\n def Mesh \"h\" { int[] faceVertexCounts = [3]\n"
      "  int[] faceVertexIndices = [0, 1, 2]\n point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)] } }\n"
      "def Mesh \"off\" ( active = false ) { int[] faceVertexCounts = [3]\n int[] faceVertexIndices = [0, 1, 2]\n"
      "  point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)] }\n"
      "class \"abstract\" { def Mesh \"no\" { int[] faceVertexCounts = [3]\n int[] faceVertexIndices = [0, 1, 2]\n"
      "  point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)] } }\n";
  const LoadedCage cage = parse_usd(text, "v.usda");
  // The selected variant's mesh and the referenced mesh; not /src (referenced), the class, the
  // invisible Xform's mesh or the inactive mesh.
  ASSERT_EQ(cage.usd.meshes.size(), 2u);
  // The prim's own children first, then those its variant brings.
  EXPECT_EQ(cage.usd.meshes[0].path, "/root/ref/m");
  EXPECT_EQ(cage.usd.meshes[1].path, "/root/vb");
  EXPECT_EQ(cage.input.positions[0][2], 1);  // the earliest time sample (time 1), not the first written
  EXPECT_EQ(cage.input.positions[3][0], 7);
  EXPECT_EQ(cage.input.face_indices, (std::vector<int>{0, 1, 2, 3, 5, 4}));
  ASSERT_EQ(cage.usd.variant_sets.size(), 1u);
  EXPECT_EQ(cage.usd.variant_sets[0].selection, "b");
  EXPECT_EQ(cage.usd.variant_sets[0].variants, (std::vector<std::string>{"a", "b"}));
  UsdReadOptions pick;
  add_variant_selection(pick, "look=a");
  const LoadedCage a = parse_usd(text, "v.usda", pick);
  EXPECT_EQ(a.usd.meshes[1].path, "/root/va");
  EXPECT_EQ(a.input.positions[3][0], 5);
  add_variant_selection(pick, "nosuch=x");
  EXPECT_THROW(parse_usd(text, "v.usda", pick), InputError);
  EXPECT_THROW(add_variant_selection(pick, "noequals"), Error);
}

// --- hostile input ----------------------------------------------------------------------------

std::string error_of(const std::string& bytes, const std::string& name = "bad.usd") {
  try {
    parse_usd(bytes, name);
  } catch (const InputError& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    return e.what();
  }
  return "";
}

void expect_error(const std::string& bytes, const std::string& needle) {
  const std::string what = error_of(bytes);
  EXPECT_NE(what.find("bad.usd"), std::string::npos) << what;
  EXPECT_NE(what.find(needle), std::string::npos) << "expected '" << needle << "' in: " << what;
}

TEST(UsdReaderHostile, TruncatedCratesAreRefusedAtEveryLength) {
  const std::string good = as_usdc(box());
  ASSERT_NO_THROW(parse_usd(good, "good.usdc"));
  int refused = 0;
  for (std::size_t n = 0; n < good.size(); n += 7) {
    const std::string what = error_of(good.substr(0, n));
    EXPECT_FALSE(what.empty()) << "truncated to " << n << " bytes was accepted";
    refused += !what.empty();
  }
  EXPECT_GT(refused, 10);
  expect_error(good.substr(0, 50), "shorter than the 88-byte");
  expect_error(good.substr(0, good.size() - 40), "corrupt USD crate file");
}

TEST(UsdReaderHostile, CountsBeyondTheBytesAndIndicesOutOfRange) {
  const Cage c = box();
  // A points array claiming 2^40 elements.
  {
    std::string bytes = as_usdc(c, false);
    const std::string needle(reinterpret_cast<const char*>(&c.points[0]), 12);  // first point (0, 0, 0)
    const std::size_t at = bytes.find(std::string("\x0c\0\0\0\0\0\0\0", 8) + needle);  // count 12 then the point
    ASSERT_NE(at, std::string::npos);
    const std::uint64_t huge = 1ull << 40;
    std::memcpy(bytes.data() + at, &huge, 8);
    expect_error(bytes, "claims");
  }
  // The table of contents beyond the end of the file.
  {
    std::string bytes = as_usdc(c);
    const std::uint64_t toc = bytes.size() + 1000;
    std::memcpy(bytes.data() + 16, &toc, 8);
    expect_error(bytes, "table of contents");
  }
  // A face vertex out of range, in text and in the crate.
  {
    Cage bad = c;
    bad.indices[5] = 99;
    expect_error(as_usda(bad), "faceVertexIndices entry 5 is vertex 99");
    expect_error(as_usdc(bad), "faceVertexIndices entry 5 is vertex 99");
    bad = c;
    bad.crease = {0, 1, 40};
    expect_error(as_usda(bad), "creaseIndices names vertex 40");
  }
  // faceVertexCounts not adding up; a crease sharpness count that fits neither reading.
  expect_error(mesh_with_ops("", "").replace(mesh_with_ops("", "").find("[4]"), 3, "[5]"), "adds up to 5");
  expect_error(mesh_with_ops("", "        int[] creaseIndices = [0, 1, 2]\n        int[] creaseLengths = [3]\n"
                                 "        float[] creaseSharpnesses = [1, 2, 3]\n"),
               "neither one per crease");
  // A mesh that is not there.
  expect_error("#usda 1.0\ndef Xform \"x\" {}\n", "no Mesh prim");
  expect_error("not usd at all", "not a USD file");
}

TEST(UsdReaderHostile, CyclicPathsReferencesAndAbsurdNesting) {
  // Paths: a jump table whose sibling jump points back into the tree.
  {
    CrateWriter w;
    const int a = w.path(0, "a");
    w.path(0, "b");
    w.spec(0, CrateWriter::kPseudoRoot, {});
    w.spec(a, CrateWriter::kPrim, {{"specifier", w.specifier(0)}});
    std::string bytes = w.finish();
    // The PATHS section's tables, coded by the writer: jumps [root: child only, a: sibling next,
    // b: leaf], path indexes [0, 1, 2]. A jump past the end, and a path defined twice (the only
    // way an encoded tree can loop back) are refused.
    auto patched = [&](const std::vector<std::int32_t>& good, const std::vector<std::int32_t>& bad) {
      std::string copy = bytes;
      const std::string g = CrateWriter::compress_ints(good), b = CrateWriter::compress_ints(bad);
      const std::size_t at = copy.find(g);
      EXPECT_NE(at, std::string::npos);
      EXPECT_EQ(g.size(), b.size());
      if (at != std::string::npos && g.size() == b.size()) copy.replace(at, b.size(), b);
      return copy;
    };
    expect_error(patched({-1, 0, -2}, {-1, 0, 0}), "PATHS jumps to entry 3 of 3");
    expect_error(patched({0, 1, 2}, {0, 1, 1}), "PATHS defines path 1 twice");
  }
  // References in a cycle.
  expect_error("#usda 1.0\ndef \"a\" ( references = </b> ) {}\ndef \"b\" ( references = </a> ) {}\n"
               "def \"c\" ( references = </a> ) {}\n",
               "cyclic");
  // Nesting: 1000 prims deep, and 100000 nested brackets in a value.
  {
    std::string deep = "#usda 1.0\n";
    for (int i = 0; i < 1000; ++i) deep += "def \"p" + std::to_string(i) + "\" {\n";
    deep += std::string(1000, '}');
    expect_error(deep, "nesting deeper");
    std::string brackets = "#usda 1.0\ndef Mesh \"m\" { int[] x = " + std::string(100000, '[') + "\n}\n";
    expect_error(brackets, "nesting deeper");
  }
  // A usdz whose entry runs past the end.
  {
    std::string zip = "PK\x03\x04";
    zip += std::string(14, '\0');
    const std::uint32_t size = 1000;
    zip.append(reinterpret_cast<const char*>(&size), 4).append(reinterpret_cast<const char*>(&size), 4);
    const std::uint16_t name_length = 6, extra = 0;
    zip.append(reinterpret_cast<const char*>(&name_length), 2).append(reinterpret_cast<const char*>(&extra), 2);
    zip += "a.usda#usda 1.0\n";
    expect_error(zip, "runs past the end");
  }
}

TEST(UsdReader, UsdzStoredLayerIsRead) {
  const std::string layer = as_usda(box());
  std::string zip = "PK\x03\x04";
  zip += std::string(4, '\0');  // version, flags
  zip += std::string(2, '\0');  // method 0: stored
  zip += std::string(8, '\0');  // time, date, crc (not checked)
  const std::uint32_t size = static_cast<std::uint32_t>(layer.size());
  zip.append(reinterpret_cast<const char*>(&size), 4).append(reinterpret_cast<const char*>(&size), 4);
  const std::string name = "box.usda";
  const std::uint16_t name_length = static_cast<std::uint16_t>(name.size()), extra = 0;
  zip.append(reinterpret_cast<const char*>(&name_length), 2).append(reinterpret_cast<const char*>(&extra), 2);
  zip += name + layer;
  const LoadedCage cage = parse_usd(zip, "box.usdz");
  EXPECT_EQ(cage.usd.encoding, "usdz/usda");
  expect_same_input(cage.input, parse_usd(layer, "box.usda").input);
}

}  // namespace
}  // namespace subd2nurbs
