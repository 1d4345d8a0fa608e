#include "core/patch/local_mesh.h"

#include <algorithm>
#include <stdexcept>
#include <utility>

#include "core/mesh/marks.h"

namespace subd2nurbs {

std::vector<int> face_rings(const PolyMesh& m, const std::vector<int>& seed_vertices, int rings) {
  thread_local std::vector<int> face_store, vertex_store;
  Marks face_seen(face_store, m.num_faces()), vertex_seen(vertex_store, m.num_vertices());
  std::vector<int> vertices, faces;
  for (int v : seed_vertices)
    if (vertex_seen.set(v, 1)) vertices.push_back(v);
  size_t ring_start = 0;  // the vertices whose faces are still to be collected
  for (int r = 0; r < rings; ++r) {
    const size_t first_new_face = faces.size();
    for (size_t k = ring_start; k < vertices.size(); ++k) {
      const int v = vertices[k];
      const int* c = m.vertex_corners(v);
      for (int i = 0; i < m.vertex_face_count(v); ++i)
        if (face_seen.set(m.corner_face(c[i]), 1)) faces.push_back(m.corner_face(c[i]));
    }
    if (r + 1 == rings) break;
    ring_start = vertices.size();
    for (size_t k = first_new_face; k < faces.size(); ++k)
      for (int h = m.face_begin(faces[k]); h < m.face_end(faces[k]); ++h)
        if (vertex_seen.set(m.corner_vertex(h), 1)) vertices.push_back(m.corner_vertex(h));
  }
  std::sort(faces.begin(), faces.end());
  return faces;
}

std::vector<int> vertices_of(const PolyMesh& m, const std::vector<int>& faces) {
  thread_local std::vector<int> store;
  Marks seen(store, m.num_vertices());
  std::vector<int> out;
  for (int f : faces)
    for (int h = m.face_begin(f); h < m.face_end(f); ++h)
      if (seen.set(m.corner_vertex(h), 1)) out.push_back(m.corner_vertex(h));
  std::sort(out.begin(), out.end());
  return out;
}

namespace {

constexpr float kInf = static_cast<float>(kInfiniteSharpness);

}  // namespace

LocalMesh cut_out(const SubdivLevel& level, const std::vector<Point3>& x, const std::vector<int>& faces,
                  const std::vector<int>& origin_face, const std::vector<int>& origin_vertex) {
  const PolyMesh& m = level.mesh;
  const int nf = static_cast<int>(faces.size());
  // Where each chosen face sits in `faces` (a face listed twice keeps its first place).
  thread_local std::vector<int> store;
  Marks position(store, m.num_faces());
  for (int i = 0; i < nf; ++i) position.set(faces[i], i);
  auto local_face = [&](int f) { return position.get(f); };
  // The piece's corners: those of face i start at first_corner[i].
  std::vector<int> first_corner(nf + 1, 0);
  for (int i = 0; i < nf; ++i) first_corner[i + 1] = first_corner[i] + m.face_size(faces[i]);
  auto local_corner = [&](int h) {  // -1 when h's face is not chosen
    const int f = m.corner_face(h), i = local_face(f);
    return i < 0 ? -1 : first_corner[i] + (h - m.face_begin(f));
  };

  // One local vertex per run of consecutive chosen faces around each source vertex. The runs
  // are also the local vertices' fans, in the source's fan order (each next corner is
  // twin(prev(corner))): a run starts where the source fan leaves the piece, which is the
  // local boundary, and a closed fan starts at its smallest local corner, as PolyMesh::build
  // orders them; so the mesh is assembled directly, without PolyMesh::build's search.
  const int nc = first_corner[nf];
  std::vector<int> vertex_of_corner(nc, -1);  // piece corner -> local vertex
  LocalMesh out;
  out.x.reserve(nc);
  out.origin_vertex.reserve(nc);
  out.level.vertex_sharpness.reserve(nc);
  PolyMesh& lm = out.level.mesh;
  auto& vertex_offsets = PolyMeshAssembler::vertex_offsets(lm);
  auto& vertex_corners = PolyMeshAssembler::vertex_corners(lm);
  vertex_offsets.assign(1, 0);
  vertex_corners.reserve(nc);
  auto new_vertex = [&](int v) {
    out.x.push_back(x[v]);
    out.origin_vertex.push_back(origin_vertex.empty() ? v : origin_vertex[v]);
    out.level.vertex_sharpness.push_back(level.vertex_sharpness[v]);
    return static_cast<int>(out.x.size()) - 1;
  };
  std::vector<int> around;  // piece corner of each corner around v, -1 outside the piece
  for (int i = 0; i < nf; ++i)
    for (int k = first_corner[i]; k < first_corner[i + 1]; ++k) {
      if (vertex_of_corner[k] >= 0) continue;
      const int v = m.corner_vertex(m.face_begin(faces[i]) + (k - first_corner[i]));
      const int* c = m.vertex_corners(v);
      const int n = m.vertex_face_count(v);
      around.resize(n);
      bool closed = !m.is_boundary_vertex(v);
      for (int j = 0; j < n; ++j) {
        around[j] = local_corner(c[j]);
        closed = closed && around[j] >= 0;
      }
      // Start after a corner outside the piece (or at the fan's start for a boundary vertex
      // or a vertex whose faces are all inside).
      int start = 0;
      if (!m.is_boundary_vertex(v))
        for (int j = 0; j < n; ++j)
          if (around[j] < 0) { start = (j + 1) % n; break; }
      if (closed) start = static_cast<int>(std::min_element(around.begin(), around.end()) - around.begin());
      int current = -1;
      for (int j = 0, at = start; j < n; ++j, at = at + 1 == n ? 0 : at + 1) {  // no division per step
        const int lc = around[at];
        if (lc < 0) {
          current = -1;
          continue;
        }
        if (current < 0) {
          current = new_vertex(v);
          vertex_offsets.push_back(static_cast<int>(vertex_corners.size()));
        }
        vertex_of_corner[lc] = current;
        vertex_corners.push_back(lc);
        vertex_offsets.back() = static_cast<int>(vertex_corners.size());
      }
    }

  // Faces, twins (a source twin inside the piece), and edges numbered in order of first
  // appearance (as PolyMesh::build numbers them).
  out.source_corner.resize(nc);
  out.origin_face.resize(nf);
  out.level.face_hole.resize(nf);
  PolyMeshAssembler::num_vertices(lm) = static_cast<int>(out.x.size());
  auto& face_offsets = PolyMeshAssembler::face_offsets(lm);
  face_offsets.assign(first_corner.begin(), first_corner.end());
  PolyMeshAssembler::corner_vertex(lm).assign(vertex_of_corner.begin(), vertex_of_corner.end());
  bool quads = true;
  for (int i = 0; i < nf; ++i) {
    const int f = faces[i];
    quads = quads && m.face_size(f) == 4;
    for (int k = first_corner[i]; k < first_corner[i + 1]; ++k) out.source_corner[k] = m.face_begin(f) + (k - first_corner[i]);
    out.origin_face[i] = origin_face.empty() ? f : origin_face[f];
    out.level.face_hole[i] = level.face_hole[f];
  }
  PolyMeshAssembler::all_quads(lm) = quads;
  auto& corner_face = PolyMeshAssembler::corner_face(lm);
  corner_face.clear();
  if (!quads) {
    corner_face.resize(nc);
    for (int i = 0; i < nf; ++i)
      for (int k = first_corner[i]; k < first_corner[i + 1]; ++k) corner_face[k] = i;
  }
  auto& twin = PolyMeshAssembler::twin(lm);
  twin.resize(nc);
  for (int k = 0; k < nc; ++k) {
    const int t = m.twin(out.source_corner[k]);
    twin[k] = t < 0 ? -1 : local_corner(t);
  }
  auto& corner_edge = PolyMeshAssembler::corner_edge(lm);
  auto& edge_corner = PolyMeshAssembler::edge_corner(lm);
  corner_edge.assign(nc, -1);
  edge_corner.clear();
  edge_corner.reserve(nc / 2 + 8);
  for (int k = 0; k < nc; ++k) {
    if (corner_edge[k] >= 0) continue;
    corner_edge[k] = static_cast<int>(edge_corner.size());
    if (twin[k] >= 0) corner_edge[twin[k]] = corner_edge[k];
    edge_corner.push_back(k);
  }
  out.level.options = level.options;
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
