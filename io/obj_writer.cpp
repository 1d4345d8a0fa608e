#include "io/obj_writer.h"

#include <algorithm>
#include <cstdio>
#include <ostream>
#include <stdexcept>
#include <string>

#include "core/analysis/mesh_stats.h"
#include "io/atomic_file.h"

namespace subd2nurbs {

namespace {

/// Buffers formatted lines; an ostream insertion per number would dominate the run time
/// for refined meshes with millions of vertices.
class LineWriter {
 public:
  explicit LineWriter(std::ostream& out) : out_(out) {}
  ~LineWriter() { flush(); }

  template <typename... Args>
  void line(const char* format, Args... args) {
    char buffer[256];
    const int n = std::snprintf(buffer, sizeof buffer, format, args...);
    if (n < 0 || n >= static_cast<int>(sizeof buffer))
      throw std::logic_error("obj_writer: formatted line too long");
    text_.append(buffer, n);
    text_ += '\n';
    if (text_.size() > (1u << 20)) flush();
  }
  void raw(const std::string& s) { text_ += s; }
  void flush() {
    out_.write(text_.data(), static_cast<std::streamsize>(text_.size()));
    text_.clear();
  }

 private:
  std::ostream& out_;
  std::string text_;
};

int boundary_tag_value(BoundaryRule rule) {
  switch (rule) {
    case BoundaryRule::None: return 0;
    case BoundaryRule::EdgeAndCorner: return 1;
    case BoundaryRule::EdgeOnly: return 2;
  }
  return 1;
}

void write_level(std::ostream& out, const std::vector<Point3>& positions,
                 const SubdivLevel& level) {
  const PolyMesh& m = level.mesh;
  LineWriter w(out);
  w.line("# Written by subd2nurbs: %d vertices, %d faces.", m.num_vertices(), m.num_faces());
  w.line("# Tags ('t' lines) use OpenSubdiv's format; their indices are 0-based.");
  for (const Point3& p : positions) w.line("v %.17g %.17g %.17g", p[0], p[1], p[2]);

  std::string face;
  for (int f = 0; f < m.num_faces(); ++f) {
    face = "f";
    const int* vertices = m.face_vertices(f);
    for (int k = 0; k < m.face_size(f); ++k) face += " " + std::to_string(vertices[k] + 1);
    face += '\n';
    w.raw(face);
  }

  const SubdivOptions& options = level.options;
  w.line("t interpolateboundary 1/0/0 %d", boundary_tag_value(options.boundary));
  if (options.crease_method == CreaseMethod::Chaikin) w.line("t creasemethod 0/0/1 chaikin");
  if (options.triangles == TriangleRule::Smooth) w.line("t smoothtriangles 0/0/1 smooth");
  const bool tag_boundary = options.boundary == BoundaryRule::None;
  for (int e = 0; e < m.num_edges(); ++e) {
    if (level.edge_sharpness[e] <= 0 || (m.is_boundary_edge(e) && !tag_boundary)) continue;
    const int a = m.edge_vertex(e, 0), b = m.edge_vertex(e, 1);
    w.line("t crease 2/1/0 %d %d %.17g", std::min(a, b), std::max(a, b),
           static_cast<double>(level.edge_sharpness[e]));
  }
  for (int v = 0; v < m.num_vertices(); ++v)
    if (level.vertex_sharpness[v] > 0 && !is_automatic_corner(level, v))
      w.line("t corner 1/1/0 %d %.17g", v, static_cast<double>(level.vertex_sharpness[v]));
  for (int f = 0; f < m.num_faces(); ++f)
    if (level.face_hole[f]) w.line("t hole 1/0/0 %d", f);
  w.flush();
}

}  // namespace

void write_obj(std::ostream& out, const std::vector<Point3>& positions, const SubdivLevel& level) {
  const PolyMesh& m = level.mesh;
  if (static_cast<int>(positions.size()) != m.num_vertices() ||
      static_cast<int>(level.edge_sharpness.size()) != m.num_edges() ||
      static_cast<int>(level.vertex_sharpness.size()) != m.num_vertices() ||
      static_cast<int>(level.face_hole.size()) != m.num_faces())
    throw std::invalid_argument("write_obj: positions or tags do not match the mesh (" +
                                std::to_string(positions.size()) + " positions for " +
                                std::to_string(m.num_vertices()) + " vertices)");
  write_level(out, positions, level);
}

void write_obj(const std::string& path, const std::vector<Point3>& positions,
               const SubdivLevel& level) {
  write_file_atomically(path, [&](std::ostream& out) { write_obj(out, positions, level); });
}

}  // namespace subd2nurbs
