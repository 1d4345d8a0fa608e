// The STL, PLY and OFF readers (io/mesh_reader.h) and their repairs. Oracle: small analytic
// meshes (a cube as 12 triangles, an octahedron, a cube of 6 quads) that the test writes itself
// in every variant of every format; each must read back to the same welded mesh, compared in a
// canonical order (vertices sorted by position, faces rotated to their smallest vertex and
// sorted), bit for bit. Then the repairs one by one, hostile inputs, and real files.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "io/cage_reader.h"
#include "io/input_error.h"
#include "io/mesh_reader.h"
#include "io/temp_dir.h"

namespace subd2nurbs {
namespace {

using Point = std::array<double, 3>;

/// A mesh to write: positions and faces (counter-clockwise seen from outside).
struct Mesh {
  std::vector<Point> positions;
  std::vector<std::vector<int>> faces;
};

Mesh cube_quads() {
  Mesh m;
  for (int i = 0; i < 8; ++i) m.positions.push_back({i & 1 ? 1.0 : -1.0, i & 2 ? 1.0 : -1.0, i & 4 ? 1.0 : -1.0});
  m.faces = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  return m;
}

Mesh cube_triangles() {
  Mesh m = cube_quads();
  std::vector<std::vector<int>> triangles;
  for (const auto& q : m.faces) {
    triangles.push_back({q[0], q[1], q[2]});
    triangles.push_back({q[0], q[2], q[3]});
  }
  m.faces = triangles;
  return m;
}

Mesh octahedron() {
  Mesh m;
  m.positions = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  m.faces = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  return m;
}

// --- writers -------------------------------------------------------------------------------

std::string number(double x) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", x);
  return buffer;
}

void put_u32(std::string& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out += static_cast<char>((v >> (8 * i)) & 0xff);
}

void put_float(std::string& out, float x) {
  std::uint32_t bits;
  std::memcpy(&bits, &x, 4);
  put_u32(out, bits);
}

/// Binary STL with the given 80-byte header text, the faces fan-triangulated.
std::string stl_binary(const Mesh& m, const std::string& header, std::uint16_t attribute = 0) {
  std::string out = header;
  out.resize(80, ' ');
  std::vector<std::array<int, 3>> triangles;
  for (const auto& f : m.faces)
    for (std::size_t i = 1; i + 1 < f.size(); ++i) triangles.push_back({f[0], f[i], f[i + 1]});
  put_u32(out, static_cast<std::uint32_t>(triangles.size()));
  for (const auto& t : triangles) {
    for (int k = 0; k < 3; ++k) put_float(out, k == 2 ? 1.0f : 0.0f);  // a wrong normal: ignored
    for (int v : t)
      for (double x : m.positions[static_cast<std::size_t>(v)]) put_float(out, static_cast<float>(x));
    out += static_cast<char>(attribute & 0xff);
    out += static_cast<char>(attribute >> 8);
  }
  return out;
}

/// ASCII STL; `solids` > 1 splits the facets over several solids; `sep` separates tokens.
std::string stl_ascii(const Mesh& m, const std::string& name, int solids = 1, const std::string& sep = " ") {
  std::string out;
  const std::size_t per = (m.faces.size() + static_cast<std::size_t>(solids) - 1) / static_cast<std::size_t>(solids);
  for (std::size_t f = 0; f < m.faces.size(); ++f) {
    if (f % per == 0) out += "solid" + (name.empty() ? "" : " " + name) + "\n";
    out += "  facet" + sep + "normal 0 0 1\n    outer loop\n";
    for (int v : m.faces[f]) {
      out += "      vertex";
      for (double x : m.positions[static_cast<std::size_t>(v)]) out += sep + number(x);
      out += "\n";
    }
    out += "    endloop\n  endfacet\n";
    if (f % per == per - 1 || f + 1 == m.faces.size()) out += "endsolid" + (name.empty() ? "" : " " + name) + "\n";
  }
  return out;
}

enum class Ply { Ascii, Little, Big };

/// PLY with the positions as float or double, optionally extra vertex and face properties
/// and an extra element with a list property between the vertices and the faces.
std::string ply(const Mesh& m, Ply format, bool doubles, bool extras) {
  std::string out = "ply\nformat ";
  out += format == Ply::Ascii ? "ascii" : format == Ply::Little ? "binary_little_endian" : "binary_big_endian";
  out += " 1.0\ncomment written by test_mesh_readers\nobj_info nothing\n";
  out += "element vertex " + std::to_string(m.positions.size()) + "\n";
  const std::string t = doubles ? "double" : "float";
  if (extras) out += "property uchar red\nproperty list uint8 int16 ignored\n";
  out += "property " + t + " x\nproperty " + t + " y\nproperty " + t + " z\n";
  if (extras) out += "property float64 confidence\n";
  if (extras) out += "element edge 2\nproperty int vertex1\nproperty list uchar int tags\n";
  out += "element face " + std::to_string(m.faces.size()) + "\n";
  if (extras) out += "property ushort flags\n";
  out += std::string("property list uchar ") + (extras ? "uint32" : "int") + " vertex_indices\n";
  if (extras) out += "property list uchar float texcoord\n";
  out += "end_header\n";
  const bool big = format == Ply::Big;
  auto raw = [&](const void* p, std::size_t n) {
    const auto* b = static_cast<const unsigned char*>(p);
    for (std::size_t i = 0; i < n; ++i) out += static_cast<char>(b[big ? n - 1 - i : i]);
  };
  auto put = [&](double x, const std::string& type) {
    if (format == Ply::Ascii) {
      out += number(x) + " ";
    } else if (type == "double") {
      raw(&x, 8);
    } else if (type == "float") {
      const float f = static_cast<float>(x);
      raw(&f, 4);
    } else if (type == "int" || type == "uint") {
      const std::int32_t i = static_cast<std::int32_t>(x);
      raw(&i, 4);
    } else if (type == "short") {
      const std::int16_t i = static_cast<std::int16_t>(x);
      raw(&i, 2);
    } else {
      const auto c = static_cast<unsigned char>(x);
      raw(&c, 1);
    }
  };
  auto end_line = [&] {
    if (format == Ply::Ascii) out += "\n";
  };
  for (const Point& p : m.positions) {
    if (extras) {
      put(200, "uchar");
      put(2, "uchar");
      put(-7, "short");
      put(300, "short");
    }
    for (double x : p) put(x, t);
    if (extras) put(0.5, "double");
    end_line();
  }
  if (extras)
    for (int e = 0; e < 2; ++e) {
      put(e, "int");
      put(3, "uchar");
      for (int k = 0; k < 3; ++k) put(k + 100, "int");
      end_line();
    }
  for (const auto& f : m.faces) {
    if (extras) put(9, "short");
    put(static_cast<double>(f.size()), "uchar");
    for (int v : f) put(v, "int");
    if (extras) {
      put(2, "uchar");
      put(0.25, "float");
      put(0.75, "float");
    }
    end_line();
  }
  return out;
}

/// OFF with comments, optionally COFF colours (per vertex and per face) and counts on the
/// keyword's line.
std::string off(const Mesh& m, bool colours, bool counts_on_keyword_line) {
  std::string out = "# a comment before the keyword\n";
  out += colours ? "COFF" : "OFF";
  out += counts_on_keyword_line ? " " : "\n# between the keyword and the counts\n\n";
  out += std::to_string(m.positions.size()) + " " + std::to_string(m.faces.size()) + " 0\n";
  for (const Point& p : m.positions) {
    out += number(p[0]) + " " + number(p[1]) + "\t" + number(p[2]);
    if (colours) out += " 255 128 0 255";
    out += "  # a vertex\n";
  }
  for (const auto& f : m.faces) {
    out += std::to_string(f.size());
    for (int v : f) out += " " + std::to_string(v);
    if (colours) out += " 0.5 0.5 0.5";
    out += "\n";
  }
  return out;
}

// --- canonical form and topology ------------------------------------------------------------

/// Vertices sorted by position; faces renumbered, rotated to start at their smallest vertex
/// and sorted. Two reads of one mesh compare equal exactly when they are the same mesh.
struct Canonical {
  std::vector<Point> positions;
  std::vector<std::vector<int>> faces;
  bool operator==(const Canonical& o) const { return positions == o.positions && faces == o.faces; }
};

Canonical canonical(const MeshInput& m) {
  std::vector<int> order(m.positions.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return m.positions[static_cast<std::size_t>(a)] < m.positions[static_cast<std::size_t>(b)];
  });
  std::vector<int> rank(order.size());
  Canonical c;
  for (std::size_t i = 0; i < order.size(); ++i) {
    rank[static_cast<std::size_t>(order[i])] = static_cast<int>(i);
    c.positions.push_back(m.positions[static_cast<std::size_t>(order[i])]);
  }
  std::size_t o = 0;
  for (int n : m.face_sizes) {
    std::vector<int> f;
    for (int k = 0; k < n; ++k) f.push_back(rank[static_cast<std::size_t>(m.face_indices[o + static_cast<std::size_t>(k)])]);
    o += static_cast<std::size_t>(n);
    std::rotate(f.begin(), std::min_element(f.begin(), f.end()), f.end());
    c.faces.push_back(f);
  }
  std::sort(c.faces.begin(), c.faces.end());
  return c;
}

Canonical canonical(const Mesh& m) {
  MeshInput in;
  in.positions = m.positions;
  for (const auto& f : m.faces) {
    in.face_sizes.push_back(static_cast<int>(f.size()));
    in.face_indices.insert(in.face_indices.end(), f.begin(), f.end());
  }
  return canonical(in);
}

struct Topology {
  long vertices = 0, edges = 0, faces = 0, boundary_edges = 0, non_manifold_edges = 0, misoriented_edges = 0;
  long euler() const { return vertices - edges + faces; }
};

Topology topology(const MeshInput& m) {
  std::map<std::pair<int, int>, std::vector<int>> directed;  // undirected edge -> +1 / -1 uses
  std::size_t o = 0;
  for (int n : m.face_sizes) {
    for (int k = 0; k < n; ++k) {
      const int a = m.face_indices[o + static_cast<std::size_t>(k)];
      const int b = m.face_indices[o + static_cast<std::size_t>((k + 1) % n)];
      directed[{std::min(a, b), std::max(a, b)}].push_back(a < b ? 1 : -1);
    }
    o += static_cast<std::size_t>(n);
  }
  Topology t;
  t.vertices = m.num_vertices();
  t.faces = m.num_faces();
  t.edges = static_cast<long>(directed.size());
  for (const auto& [edge, uses] : directed) {
    if (uses.size() == 1) ++t.boundary_edges;
    if (uses.size() > 2) ++t.non_manifold_edges;
    if (uses.size() == 2 && uses[0] == uses[1]) ++t.misoriented_edges;
  }
  return t;
}

/// Signed volume of a closed mesh (positive when its faces point outward).
double volume(const MeshInput& m) {
  double v = 0;
  std::size_t o = 0;
  for (int n : m.face_sizes) {
    const Point& a = m.positions[static_cast<std::size_t>(m.face_indices[o])];
    for (int k = 1; k + 1 < n; ++k) {
      const Point& b = m.positions[static_cast<std::size_t>(m.face_indices[o + static_cast<std::size_t>(k)])];
      const Point& c = m.positions[static_cast<std::size_t>(m.face_indices[o + static_cast<std::size_t>(k) + 1])];
      v += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
    }
    o += static_cast<std::size_t>(n);
  }
  return v / 6;
}

/// The InputError a call throws (fails the test when there is none).
InputError error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "no InputError";
  return InputError("", 0, "(none)");
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// --- every variant reads to the same mesh ----------------------------------------------------

struct Variant {
  std::string file, bytes;
};

std::vector<Variant> triangle_variants(const Mesh& m) {
  return {
      {"plain.stl", stl_binary(m, "binary STL written by a test")},
      {"solid_header.STL", stl_binary(m, "solid header of a binary file")},
      {"color.stl", stl_binary(m, "COLOR=\xff\x80\x01\xff,MATERIAL=\x10\x20\x30\x40\x50\x60\x70\x80\x90\xa0\xb0\xc0", 0x801f)},
      {"ascii.stl", stl_ascii(m, "")},
      {"named_two_solids.stl", stl_ascii(m, "my part", 2, " \t ")},
      {"ascii.ply", ply(m, Ply::Ascii, false, false)},
      {"ascii_extras.ply", ply(m, Ply::Ascii, true, true)},
      {"little.ply", ply(m, Ply::Little, false, false)},
      {"little_extras.ply", ply(m, Ply::Little, true, true)},
      {"big.ply", ply(m, Ply::Big, false, true)},
      {"big_double.PLY", ply(m, Ply::Big, true, true)},
      {"comments.off", off(m, false, false)},
      {"colours.off", off(m, true, true)},
  };
}

TEST(MeshReaders, EveryTriangleVariantReadsToTheSameMesh) {
  testing::TempDir dir;
  for (const auto& [shape, mesh, quads] :
       std::vector<std::tuple<std::string, Mesh, int>>{{"cube", cube_triangles(), 6}, {"octahedron", octahedron(), 0}}) {
    // The reference: the analytic mesh, with the cube's triangle pairs recovered as quads.
    const Canonical expected = canonical(shape == "cube" ? cube_quads() : mesh);
    for (const Variant& v : triangle_variants(mesh)) {
      SCOPED_TRACE(shape + " " + v.file);
      const LoadedCage cage = read_cage(dir.write(v.file, v.bytes));
      EXPECT_EQ(canonical(cage.input), expected);
      EXPECT_TRUE(cage.repair.applied);
      EXPECT_TRUE(cage.repair.triangles_only);
      EXPECT_TRUE(cage.recovery.applied);
      EXPECT_EQ(cage.recovery.quads, quads);
      EXPECT_TRUE(cage.diagnostics.empty());  // nothing repaired: no warning
      EXPECT_EQ(cage.repair.vertices_merged_near + cage.repair.faces_flipped + cage.repair.components_reversed + cage.repair.degenerate_faces +
                    cage.repair.duplicate_faces + cage.repair.unused_vertices,
                0);
      EXPECT_EQ(cage.repair.closed_components, 1);
      EXPECT_EQ(cage.face_line.size(), cage.input.face_sizes.size());
      EXPECT_EQ(cage.vertex_line.size(), cage.input.positions.size());
      for (int loc : cage.face_line) EXPECT_GT(loc, 0);
      EXPECT_NO_THROW(validate_cage(cage));
    }
  }
}

TEST(MeshReaders, QuadMeshIsTakenAsItIs) {
  testing::TempDir dir;
  const Mesh m = cube_quads();
  const Canonical expected = canonical(m);
  for (const Variant& v : std::vector<Variant>{{"a.ply", ply(m, Ply::Ascii, false, true)},
                                               {"l.ply", ply(m, Ply::Little, true, true)},
                                               {"b.ply", ply(m, Ply::Big, true, false)},
                                               {"c.off", off(m, false, false)},
                                               {"d.off", off(m, true, true)}}) {
    SCOPED_TRACE(v.file);
    const LoadedCage cage = read_cage(dir.write(v.file, v.bytes));
    EXPECT_EQ(canonical(cage.input), expected);
    EXPECT_FALSE(cage.repair.triangles_only);
    EXPECT_FALSE(cage.recovery.applied);
  }
  // Positions that need every bit of a double survive PLY double and OFF text exactly.
  Mesh fine = m;
  for (Point& p : fine.positions)
    for (double& x : p) x = x * (1.0 / 3.0) + 0.1;
  for (const Variant& v : std::vector<Variant>{{"f.ply", ply(fine, Ply::Big, true, true)},
                                               {"g.ply", ply(fine, Ply::Ascii, true, false)},
                                               {"h.off", off(fine, true, false)}})
    EXPECT_EQ(canonical(read_cage(dir.write(v.file, v.bytes)).input), canonical(fine)) << v.file;
}

TEST(MeshReaders, LocationsAreLinesOrElements) {
  // OFF: the lines of the vertex and face statements.
  const LoadedCage o = parse_off("OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n", "q.off");
  EXPECT_EQ(o.locator, LoadedCage::Locator::Line);
  EXPECT_EQ(o.vertex_line, (std::vector<int>{3, 4, 5, 6}));
  EXPECT_EQ(o.face_line, (std::vector<int>{7}));
  // Binary STL: facet numbers (1-based; 0 means unknown).
  const LoadedCage s = parse_stl(stl_binary(octahedron(), ""), "o.stl");
  EXPECT_EQ(s.locator, LoadedCage::Locator::Element);
  EXPECT_EQ(s.face_line, (std::vector<int>{1, 2, 3, 4, 5, 6, 7, 8}));
  EXPECT_EQ(s.vertex_line[0], 1);
}

// --- repairs ---------------------------------------------------------------------------------

TEST(MeshReaders, JitteredSoupWeldsToTheCleanMesh) {
  Mesh soup;
  const Mesh cube = cube_triangles();
  std::uint32_t state = 12345;
  auto jitter = [&] {
    state = state * 1664525u + 1013904223u;
    return (static_cast<double>(state >> 8) / (1 << 24) - 0.5) * 2e-9;
  };
  for (const auto& f : cube.faces) {
    std::vector<int> face;
    for (int v : f) {
      Point p = cube.positions[static_cast<std::size_t>(v)];
      for (double& x : p) x += jitter();
      face.push_back(static_cast<int>(soup.positions.size()));
      soup.positions.push_back(p);
    }
    soup.faces.push_back(face);
  }
  const LoadedCage cage = parse_stl(stl_ascii(soup, "jittered"), "soup.stl");
  EXPECT_EQ(cage.repair.vertices_merged, 36 - 8);
  EXPECT_EQ(cage.repair.vertices_merged_near, 36 - 8);
  ASSERT_EQ(cage.input.num_vertices(), 8);
  EXPECT_EQ(cage.input.num_faces(), 6);
  // The first of each cluster represents it: within the jitter of the clean cube, which
  // rounding the positions gives back exactly.
  MeshInput rounded = cage.input;
  for (Point& p : rounded.positions)
    for (double& x : p) {
      EXPECT_NEAR(std::abs(x), 1, 1e-9);
      x = std::round(x);
    }
  EXPECT_EQ(canonical(rounded), canonical(cube_quads()));
  // Without welding (tolerance 0) the soup stays 12 separate triangles.
  MeshReadOptions exact;
  exact.weld_tolerance = 0;
  const LoadedCage unwelded = parse_stl(stl_ascii(soup, "jittered"), "soup.stl", exact);
  EXPECT_EQ(unwelded.input.num_vertices(), 36);
  EXPECT_EQ(unwelded.repair.components, 12);
}

TEST(MeshReaders, CrackCloses) {
  // The cube of quads with the top face on vertices of its own, 1e-10 away: a crack.
  Mesh m = cube_quads();
  std::vector<int>& top = m.faces[1];
  for (int& v : top) {
    Point p = m.positions[static_cast<std::size_t>(v)];
    p[0] += 1e-10;
    v = static_cast<int>(m.positions.size());
    m.positions.push_back(p);
  }
  MeshReadOptions exact;
  exact.weld_tolerance = 0;
  EXPECT_EQ(topology(parse_off(off(m, false, false), "c.off", exact).input).boundary_edges, 8);
  const LoadedCage cage = parse_off(off(m, false, false), "c.off");
  EXPECT_EQ(cage.repair.vertices_merged, 4);
  EXPECT_EQ(cage.repair.vertices_merged_near, 4);
  ASSERT_EQ(cage.diagnostics.size(), 1u);
  EXPECT_TRUE(contains(cage.diagnostics[0].message, "4 vertices welded onto a different position")) << cage.diagnostics[0].message;
  const Topology t = topology(cage.input);
  EXPECT_EQ(t.boundary_edges, 0);
  EXPECT_EQ(t.euler(), 2);
  EXPECT_EQ(cage.input.num_vertices(), 8);
}

TEST(MeshReaders, ToleranceStaysBelowTheShortestEdge) {
  // A long thin box, 1000 x 1e-6 x 2: 1e-7 x the diagonal (1e-4) would collapse its 1e-6 edges;
  // the cap keeps the tolerance at a tenth of them.
  Mesh m = cube_quads();
  for (Point& p : m.positions) {
    p[0] *= 500;
    p[1] *= 5e-7;
  }
  const LoadedCage cage = parse_off(off(m, false, false), "thin.off");
  EXPECT_EQ(cage.input.num_vertices(), 8);
  EXPECT_EQ(cage.repair.vertices_merged, 0);
  EXPECT_LE(cage.repair.weld_tolerance, 1e-7);
  EXPECT_EQ(canonical(cage.input), canonical(m));
}

TEST(MeshReaders, DegenerateAndDuplicateFacesAreDroppedAndCounted) {
  Mesh m = octahedron();
  m.positions.push_back({0, 1, 0});      // vertex 6 welds onto vertex 2
  m.faces.push_back({0, 2, 6});          // collapses: degenerate
  m.faces.push_back({4, 4, 1});          // a repeated index: degenerate
  m.faces.push_back({4, 2, 0});          // face 0 reversed: a duplicate
  m.faces.push_back({2, 1, 4});          // face 1 again: a duplicate
  const LoadedCage cage = parse_off(off(m, false, false), "d.off");
  EXPECT_EQ(cage.repair.degenerate_faces, 2);
  EXPECT_EQ(cage.repair.duplicate_faces, 2);
  EXPECT_EQ(cage.repair.vertices_merged, 1);
  EXPECT_EQ(canonical(cage.input), canonical(octahedron()));
  // An unused vertex is removed and counted.
  Mesh extra = octahedron();
  extra.positions.push_back({5, 5, 5});
  const LoadedCage e = parse_ply(ply(extra, Ply::Ascii, true, false), "e.ply");
  EXPECT_EQ(e.repair.unused_vertices, 1);
  EXPECT_EQ(e.input.num_vertices(), 6);
  // The summary is a warning that info and convert print.
  ASSERT_FALSE(cage.diagnostics.empty());
  EXPECT_TRUE(contains(cage.diagnostics.back().message, "2 degenerate faces dropped")) << cage.diagnostics.back().message;
}

TEST(MeshReaders, FlippedFacesAreReorientedAndCounted) {
  Mesh m = octahedron();
  std::reverse(m.faces[3].begin(), m.faces[3].end());
  const LoadedCage one = parse_stl(stl_binary(m, ""), "f.stl");
  EXPECT_EQ(one.repair.faces_flipped, 1);
  EXPECT_EQ(one.repair.components_reversed, 0);
  EXPECT_EQ(canonical(one.input), canonical(octahedron()));
  // All faces inward: the closed surface is turned outward, as a whole.
  Mesh inward = octahedron();
  for (auto& f : inward.faces) std::reverse(f.begin(), f.end());
  const LoadedCage turned = parse_off(off(inward, false, false), "i.off");
  EXPECT_EQ(turned.repair.faces_flipped, 0);
  EXPECT_EQ(turned.repair.components_reversed, 1);
  EXPECT_EQ(canonical(turned.input), canonical(octahedron()));
  EXPECT_GT(volume(turned.input), 0);
  // An open surface keeps the orientation most of its faces have.
  Mesh open = octahedron();
  open.faces.resize(4);  // the upper half
  std::reverse(open.faces[2].begin(), open.faces[2].end());
  const LoadedCage half = parse_off(off(open, false, false), "h.off");
  EXPECT_EQ(half.repair.faces_flipped, 1);
  EXPECT_EQ(half.repair.closed_components, 0);
  Mesh upper = octahedron();
  upper.faces.resize(4);
  upper.positions.pop_back();  // the lower apex, unused
  EXPECT_EQ(canonical(half.input), canonical(upper));
}

TEST(MeshReaders, NonManifoldEdgeNamesTheFace) {
  const std::string text = "OFF\n5 3 0\n0 0 0\n1 0 0\n0 1 0\n0 -1 0\n0 0 1\n3 0 1 2\n3 1 0 3\n3 0 1 4\n";
  const InputError e = error_of([&] { parse_off(text, "n.off"); });
  EXPECT_EQ(e.line(), 10);
  EXPECT_EQ(e.code(), MeshErrorCode::NonManifoldEdge);
  EXPECT_TRUE(contains(e.message(), "lines 8, 9, 10")) << e.what();
  // In binary STL: the facet's number.
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  m.faces = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  const InputError s = error_of([&] { parse_stl(stl_binary(m, ""), "n.stl"); });
  EXPECT_EQ(s.line(), 0);
  EXPECT_TRUE(contains(s.message(), "facet 2: non-manifold edge")) << s.what();
  EXPECT_TRUE(contains(s.message(), "facets 0, 1, 2")) << s.what();
}

TEST(MeshReaders, MoebiusStripNamesTheFace) {
  // A Moebius strip of 8 segments, triangulated.
  Mesh m;
  const int n = 8;
  for (int i = 0; i < n; ++i) {
    const double u = 2 * 3.14159265358979 * i / n;
    for (double s : {-0.3, 0.3})
      m.positions.push_back({(1 + s * std::cos(u / 2)) * std::cos(u), (1 + s * std::cos(u / 2)) * std::sin(u),
                             s * std::sin(u / 2)});
  }
  for (int i = 0; i < n; ++i) {
    const int a = 2 * i, b = 2 * i + 1;
    // Half a turn after segment n-1 the sides swap.
    const int c = i + 1 < n ? 2 * i + 2 : 1, d = i + 1 < n ? 2 * i + 3 : 0;
    m.faces.push_back({a, c, d});
    m.faces.push_back({a, d, b});
  }
  const InputError e = error_of([&] { parse_off(off(m, false, false), "m.off"); });
  EXPECT_EQ(e.code(), MeshErrorCode::InconsistentOrientation);
  EXPECT_GT(e.line(), 3);
  EXPECT_TRUE(contains(e.message(), "not orientable")) << e.what();
}

TEST(MeshReaders, PointCloudHasNoFaces) {
  const std::string text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                           "property float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
  const LoadedCage cage = parse_ply(text, "p.ply");
  EXPECT_TRUE(cage.repair.point_cloud);
  EXPECT_EQ(cage.input.num_vertices(), 3);
  EXPECT_EQ(cage.input.num_faces(), 0);
  EXPECT_EQ(error_of([&] { validate_cage(cage); }).code(), MeshErrorCode::EmptyMesh);
}

// --- hostile inputs ----------------------------------------------------------------------------

TEST(MeshReaders, HostileInputsAreRefusedWithTheirReason) {
  const Mesh m = octahedron();
  // Binary STL: truncated (not a "solid" header), and a "solid" header with the wrong size.
  std::string stl = stl_binary(m, "binary");
  EXPECT_TRUE(contains(error_of([&] { parse_stl(stl.substr(0, stl.size() - 7), "t.stl"); }).message(), "truncated"));
  std::string count = stl;
  count[83] = '\x40';  // 2^30 facets announced
  EXPECT_TRUE(contains(error_of([&] { parse_stl(count, "t.stl"); }).message(), "announce 1073741832 facets"));
  const std::string solid = stl_binary(m, "solid but binary");
  EXPECT_TRUE(contains(error_of([&] { parse_stl(solid.substr(0, 300), "s.stl"); }).message(), "neither binary STL"));
  EXPECT_TRUE(contains(error_of([&] { parse_stl("abc", "e.stl"); }).message(), "not an STL file"));
  // NaN: named by the facet (binary) or the line (ASCII).
  std::string nan = stl;
  const float q = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(&nan[84 + 50 * 5 + 12 + 12 + 4], &q, 4);
  const InputError n1 = error_of([&] { parse_stl(nan, "nan.stl"); });
  EXPECT_EQ(n1.code(), MeshErrorCode::NonFiniteCoordinate);
  EXPECT_TRUE(contains(n1.message(), "facet 5: vertex has a non-finite y coordinate (NaN)")) << n1.what();
  const InputError n2 = error_of([] { parse_off("OFF\n3 1 0\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n", "nan.off"); });
  EXPECT_EQ(n2.line(), 4);
  EXPECT_EQ(n2.code(), MeshErrorCode::NonFiniteCoordinate);
  // PLY: a count beyond the bytes, a list count of 2^31, a huge list in a skipped element.
  const std::string header = "ply\nformat binary_little_endian 1.0\nelement vertex 10000000\nproperty float x\n"
                             "property float y\nproperty float z\nend_header\n";
  const InputError p1 = error_of([&] { parse_ply(header + std::string(24, '\0'), "c.ply"); });
  EXPECT_EQ(p1.line(), 3);
  EXPECT_TRUE(contains(p1.message(), "announces 10000000 items, but only 24 bytes follow")) << p1.what();
  std::string many = header;
  many.replace(many.find("10000000"), 8, "1000000000");
  EXPECT_TRUE(contains(error_of([&] { parse_ply(many, "c.ply"); }).message(), "at most 100000000 are read"));
  std::string big_list = ply(m, Ply::Little, false, false);
  const std::size_t face_start = big_list.find("end_header\n") + 11 + 6 * 12;
  big_list[face_start] = '\xff';  // uchar count 255: within the bytes? no: the list runs past the end
  EXPECT_TRUE(contains(error_of([&] { parse_ply(big_list, "l.ply"); }).message(), "ends inside face 0"));
  std::string list31 = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                       "property float z\nelement face 1\nproperty list uint int vertex_indices\nend_header\n" +
                       std::string(36, '\0');
  put_u32(list31, 0x80000000u);
  const InputError p2 = error_of([&] { parse_ply(list31, "l.ply"); });
  EXPECT_EQ(p2.code(), MeshErrorCode::FaceTooLarge);
  EXPECT_TRUE(contains(p2.message(), "face 0: face has 2147483648 vertices")) << p2.what();
  std::string skipped = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                         "property float z\nelement extra 1\nproperty list uint int data\nend_header\n" +
                         std::string(36, '\0');
  put_u32(skipped, 0x80000000u);
  EXPECT_TRUE(contains(error_of([&] { parse_ply(skipped, "s.ply"); }).message(), "ends inside extra 0"));
  // A skipped element of fixed size one item longer than the bytes: refused, not skipped past
  // the end (the face element after it would be read from beyond the file).
  std::string past = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                     "property float z\nelement extra 2\nproperty int a\nelement face 1\n"
                     "property list uchar int vertex_indices\nend_header\n" + std::string(40, '\0');
  EXPECT_TRUE(contains(error_of([&] { parse_ply(past, "p.ply"); }).message(), "announces 2 items, but only 4 bytes"));
  // Negative and out-of-range indices name the face.
  const InputError i1 = error_of([] { parse_off("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n", "i.off"); });
  EXPECT_EQ(i1.line(), 6);
  EXPECT_EQ(i1.code(), MeshErrorCode::IndexOutOfRange);
  EXPECT_TRUE(contains(i1.message(), "vertex -1")) << i1.what();
  const InputError i2 = error_of([] {
    parse_ply("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
              "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n",
              "i.ply");
  });
  EXPECT_EQ(i2.line(), 13);
  EXPECT_TRUE(contains(i2.message(), "refers to vertex 3, but the file defines 3 vertices")) << i2.what();
  // OFF: absurd counts, and a face that runs past its line.
  EXPECT_TRUE(contains(error_of([] { parse_off("OFF\n99999999 1 0\n0 0 0\n", "a.off"); }).message(), "only"));
  EXPECT_TRUE(contains(error_of([] { parse_off("OFF 999999999999 1 0\n", "a.off"); }).message(), "at most"));
  EXPECT_TRUE(contains(error_of([] { parse_off("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", "f.off"); }).message(),
                       "announces 4 vertices but 3"));
  EXPECT_TRUE(contains(error_of([] { parse_ply("ply\nformat ascii 2.0\nend_header\n", "v.ply"); }).message(), "version"));
  EXPECT_TRUE(contains(error_of([] { parse_ply("solid\n", "v.ply"); }).message(), "not a PLY file"));
}

// --- real files ---------------------------------------------------------------------------------

const std::string kMeshData = std::string(SUBD2NURBS_TEST_DATA_DIR) + "/mesh/";

/// A closed, manifold, consistently and outward oriented valid cage of this Euler characteristic.
void expect_closed_manifold(const LoadedCage& cage, long euler) {
  const Topology t = topology(cage.input);
  EXPECT_EQ(t.boundary_edges, 0);
  EXPECT_EQ(t.non_manifold_edges, 0);
  EXPECT_EQ(t.misoriented_edges, 0);
  EXPECT_EQ(t.euler(), euler);
  EXPECT_GT(volume(cage.input), 0);
  EXPECT_NO_THROW(validate_cage(cage));
}

TEST(MeshReaders, FandiskIsAClosedManifold) {
  const std::string path = kMeshData + "fandisk.off";
  const LoadedCage cage = read_cage(path);
  EXPECT_TRUE(cage.repair.triangles_only);
  EXPECT_EQ(cage.repair.file_faces, 12946);
  EXPECT_EQ(cage.recovery.source_triangles, 12946);
  expect_closed_manifold(cage, 2);
  // The triangles themselves (no recovery): 12 946 faces, the same Euler characteristic.
  MeshReadOptions triangles;
  triangles.recover_quads = false;
  const LoadedCage plain = read_off(path, triangles);
  EXPECT_EQ(plain.input.num_faces(), 12946);
  EXPECT_EQ(topology(plain.input).euler(), 2);
}

TEST(MeshReaders, PlateHolesIsGenus5) {
  const LoadedCage cage = read_cage(kMeshData + "plate_holes.STL");  // binary, "solid" header
  EXPECT_EQ(cage.locator, LoadedCage::Locator::Element);
  EXPECT_EQ(cage.repair.file_faces, 1252);
  expect_closed_manifold(cage, -8);
}

TEST(MeshReaders, FeaturetypeIsGenus9OnceWelded) {
  const LoadedCage cage = read_cage(kMeshData + "featuretype.STL");
  EXPECT_EQ(cage.repair.file_faces, 3476);
  expect_closed_manifold(cage, -16);
  EXPECT_EQ(cage.repair.components, 1);
  EXPECT_GT(cage.repair.vertices_merged_near, 0);  // the cracks
  // Welding exactly equal positions only leaves the cracks open.
  MeshReadOptions exact;
  exact.weld_tolerance = 0;
  bool open = true;
  try {
    open = topology(read_stl(kMeshData + "featuretype.STL", exact).input).boundary_edges > 0;
  } catch (const InputError&) {
  }
  EXPECT_TRUE(open);
}

TEST(MeshReaders, PmpOffFilesAreTakenAsTheyAre) {
  const LoadedCage chamfer = read_cage(kMeshData + "chamfer-cube.off");
  EXPECT_FALSE(chamfer.recovery.applied);
  EXPECT_EQ(chamfer.input.num_faces(), 26);
  EXPECT_EQ(topology(chamfer.input).euler(), 2);
  EXPECT_NO_THROW(validate_cage(chamfer));
  const LoadedCage capsule = read_cage(kMeshData + "hole_capsule.off");
  EXPECT_EQ(capsule.input.num_faces(), 76);
  EXPECT_GT(topology(capsule.input).boundary_edges, 0);
  EXPECT_NO_THROW(validate_cage(capsule));
}

TEST(MeshReaders, CageReaderDispatchesByExtension) {
  testing::TempDir dir;
  const Mesh m = octahedron();
  // Upper-case extensions; an unknown extension is still read as OBJ.
  EXPECT_EQ(read_cage(dir.write("a.OFF", off(m, false, false))).input.num_faces(), 8);
  EXPECT_EQ(read_cage(dir.write("a.Stl", stl_binary(m, ""))).input.num_faces(), 8);
  EXPECT_EQ(read_cage(dir.write("a.mesh", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")).input.num_faces(), 1);
  EXPECT_EQ(read_cage(dir.write("b.txt", off(m, false, false))).input.num_faces(), 0);  // OFF text as OBJ: no faces
}

}  // namespace
}  // namespace subd2nurbs
