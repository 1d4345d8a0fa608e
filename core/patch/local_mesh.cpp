#include "core/patch/local_mesh.h"

#include <algorithm>
#include <stdexcept>
#include <unordered_map>

namespace subd2nurbs {

std::vector<int> face_rings(const PolyMesh& m, const std::vector<int>& seed_vertices, int rings) {
  std::vector<int> vertices = seed_vertices, faces;
  std::sort(vertices.begin(), vertices.end());
  vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
  for (int r = 0; r < rings; ++r) {
    faces.clear();
    for (int v : vertices) {
      const int* c = m.vertex_corners(v);
      for (int i = 0; i < m.vertex_face_count(v); ++i) faces.push_back(m.corner_face(c[i]));
    }
    std::sort(faces.begin(), faces.end());
    faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
    if (r + 1 < rings) vertices = vertices_of(m, faces);
  }
  return faces;
}

std::vector<int> vertices_of(const PolyMesh& m, const std::vector<int>& faces) {
  std::vector<int> out;
  for (int f : faces)
    for (int h = m.face_begin(f); h < m.face_end(f); ++h) out.push_back(m.corner_vertex(h));
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

namespace {

constexpr float kInf = static_cast<float>(kInfiniteSharpness);

}  // namespace

LocalMesh cut_out(const SubdivLevel& level, const std::vector<Point3>& x, const std::vector<int>& faces,
                  const std::vector<int>& origin_face, const std::vector<int>& origin_vertex) {
  const PolyMesh& m = level.mesh;
  std::unordered_map<int, int> local_face;
  local_face.reserve(faces.size() * 2);
  for (size_t i = 0; i < faces.size(); ++i) local_face.emplace(faces[i], static_cast<int>(i));
  auto inside = [&](int f) { return local_face.count(f) != 0; };

  // One local vertex per run of consecutive chosen faces around each source vertex.
  std::unordered_map<int, int> vertex_of_corner;  // source corner -> local vertex
  vertex_of_corner.reserve(faces.size() * 8);
  LocalMesh out;
  auto new_vertex = [&](int v) {
    out.x.push_back(x[v]);
    out.origin_vertex.push_back(origin_vertex.empty() ? v : origin_vertex[v]);
    out.level.vertex_sharpness.push_back(level.vertex_sharpness[v]);
    return static_cast<int>(out.x.size()) - 1;
  };
  for (int f : faces)
    for (int h = m.face_begin(f); h < m.face_end(f); ++h) {
      if (vertex_of_corner.count(h)) continue;
      const int v = m.corner_vertex(h);
      const int* c = m.vertex_corners(v);
      const int n = m.vertex_face_count(v);
      // Start after a corner outside the piece (or at the fan's start for a boundary vertex
      // or a vertex whose faces are all inside).
      int start = 0;
      if (!m.is_boundary_vertex(v))
        for (int i = 0; i < n; ++i)
          if (!inside(m.corner_face(c[i]))) { start = (i + 1) % n; break; }
      int current = -1;
      for (int i = 0; i < n; ++i) {
        const int ci = c[(start + i) % n];
        if (!inside(m.corner_face(ci))) { current = -1; continue; }
        if (current < 0) current = new_vertex(v);
        vertex_of_corner.emplace(ci, current);
      }
    }

  std::vector<int> sizes, indices;
  sizes.reserve(faces.size());
  for (int f : faces) {
    sizes.push_back(m.face_size(f));
    for (int h = m.face_begin(f); h < m.face_end(f); ++h) {
      indices.push_back(vertex_of_corner.at(h));
      out.source_corner.push_back(h);
    }
    out.origin_face.push_back(origin_face.empty() ? f : origin_face[f]);
    out.level.face_hole.push_back(level.face_hole[f]);
  }
  out.level.mesh = PolyMesh::build(static_cast<int>(out.x.size()), sizes, indices);
  out.level.options = level.options;
  const PolyMesh& lm = out.level.mesh;
  out.level.edge_sharpness.assign(lm.num_edges(), 0.0f);
  for (int e = 0; e < lm.num_edges(); ++e) {
    const int src_edge = m.corner_edge(out.source_corner[lm.edge_corner(e)]);
    out.level.edge_sharpness[e] = lm.is_boundary_edge(e) ? kInf : level.edge_sharpness[src_edge];
  }
  return out;
}

LocalMesh cut_out(const LocalMesh& piece, const std::vector<int>& faces) {
  return cut_out(piece.level, piece.x, faces, piece.origin_face, piece.origin_vertex);
}

LocalMesh refine_piece(const LocalMesh& piece) {
  RefinementStep step = refine_once(piece.level);
  LocalMesh out;
  step.stencils.apply(piece.x, out.x);
  const PolyMesh& pm = piece.level.mesh;
  out.level = std::move(step.child);
  const PolyMesh& cm = out.level.mesh;
  out.origin_face.resize(cm.num_faces());
  for (int h = 0; h < pm.num_corners(); ++h) out.origin_face[h] = piece.origin_face[pm.corner_face(h)];
  out.origin_vertex.assign(cm.num_vertices(), -1);
  for (int v = 0; v < pm.num_vertices(); ++v) out.origin_vertex[v] = piece.origin_vertex[v];
  out.source_corner.resize(cm.num_corners());
  for (int h = 0; h < cm.num_corners(); ++h) out.source_corner[h] = h;
  return out;
}

Point3 vertex_limit(const SubdivLevel& level, const std::vector<Point3>& x, int v) {
  const PolyMesh& m = level.mesh;
  std::vector<int> star;
  const int* c = m.vertex_corners(v);
  for (int i = 0; i < m.vertex_face_count(v); ++i) star.push_back(m.corner_face(c[i]));
  std::sort(star.begin(), star.end());
  LocalMesh s = cut_out(level, x, star);
  // Only v's tags matter for v's limit; clear the others so that no vertex of the star needs
  // the refining fallback of limit_stencils.
  const PolyMesh& sm = s.level.mesh;
  int lv = -1;
  for (int h = 0; h < sm.num_corners(); ++h)
    if (s.source_corner[h] == c[0]) lv = sm.corner_vertex(h);
  if (lv < 0) throw std::logic_error("vertex_limit: vertex lost in its star");
  for (int u = 0; u < sm.num_vertices(); ++u)
    if (u != lv) s.level.vertex_sharpness[u] = 0.0f;
  std::vector<char> keep(sm.num_edges(), 0);
  for_each_vertex_edge(sm, lv, [&](int e, int) { keep[e] = 1; });
  for (int e = 0; e < sm.num_edges(); ++e)
    if (!keep[e] && !sm.is_boundary_edge(e)) s.level.edge_sharpness[e] = 0.0f;
  std::fill(s.level.face_hole.begin(), s.level.face_hole.end(), 0);
  const StencilTable st = limit_stencils(s.level);
  Point3 p{0, 0, 0};
  for (int k = st.offsets[lv]; k < st.offsets[lv + 1]; ++k)
    for (int d = 0; d < 3; ++d) p[d] += st.weights[k] * s.x[st.indices[k]][d];
  return p;
}

}  // namespace subd2nurbs
