#include "core/mesh/poly_mesh.h"

#include <algorithm>
#include <numeric>
#include <tuple>
#include <utility>
#include <vector>
#include <string>

namespace subd2nurbs {

const char* to_string(MeshErrorCode code) {
  switch (code) {
    case MeshErrorCode::EmptyMesh: return "empty-mesh";
    case MeshErrorCode::NonFiniteCoordinate: return "non-finite-coordinate";
    case MeshErrorCode::FaceTooSmall: return "face-too-small";
    case MeshErrorCode::IndexOutOfRange: return "index-out-of-range";
    case MeshErrorCode::RepeatedVertexInFace: return "repeated-vertex-in-face";
    case MeshErrorCode::NonManifoldEdge: return "non-manifold-edge";
    case MeshErrorCode::InconsistentOrientation: return "inconsistent-orientation";
    case MeshErrorCode::NonManifoldVertex: return "non-manifold-vertex";
    case MeshErrorCode::InvalidTag: return "invalid-tag";
    case MeshErrorCode::CoordinateOutOfRange: return "coordinate-out-of-range";
    case MeshErrorCode::FaceTooLarge: return "face-too-large";
    case MeshErrorCode::ValenceTooHigh: return "valence-too-high";
  }
  return "unknown";
}

namespace {

[[noreturn]] void fail(MeshErrorCode code, ElementKind kind, long index, long index2,
                       const std::string& message) {
  throw InvalidMeshError(code, kind, index, index2, message);
}

std::string edge_name(int a, int b) {
  return "edge (" + std::to_string(a) + ", " + std::to_string(b) + ")";
}

}  // namespace

bool faces_orientable(const std::vector<int>& face_sizes, const std::vector<int>& face_indices) {
  // Every directed edge (lo, hi, direction, face), sorted so that an edge's faces are adjacent;
  // then a union-find of faces with the parity "reversed relative to the root": two faces that
  // traverse an edge the same way need opposite parities, else equal ones.
  std::vector<std::tuple<int, int, int, int>> edges;
  edges.reserve(face_indices.size());
  for (int f = 0, b = 0; f < static_cast<int>(face_sizes.size()); b += face_sizes[f++])
    for (int i = 0; i < face_sizes[f]; ++i) {
      const int a = face_indices[b + i], c = face_indices[b + (i + 1) % face_sizes[f]];
      edges.emplace_back(std::min(a, c), std::max(a, c), a < c ? 0 : 1, f);
    }
  std::sort(edges.begin(), edges.end());
  std::vector<int> parent(face_sizes.size()), parity(face_sizes.size(), 0), size(face_sizes.size(), 1);
  std::iota(parent.begin(), parent.end(), 0);
  const auto find = [&](int f) {  // root and f's parity relative to it (union by size: log depth)
    int p = 0;
    while (parent[f] != f) {
      p ^= parity[f];
      f = parent[f];
    }
    return std::make_pair(f, p);
  };
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i + 1;
    while (j < edges.size() && std::get<0>(edges[j]) == std::get<0>(edges[i]) &&
           std::get<1>(edges[j]) == std::get<1>(edges[i]))
      ++j;
    for (std::size_t k = i + 1; k < j; ++k) {
      const int need = std::get<2>(edges[k]) == std::get<2>(edges[i]) ? 1 : 0;
      const auto [ra, pa] = find(std::get<3>(edges[i]));
      const auto [rb, pb] = find(std::get<3>(edges[k]));
      if (ra == rb) {
        if ((pa ^ pb) != need) return false;
      } else {
        const bool a_larger = size[ra] >= size[rb];
        const int root = a_larger ? ra : rb, child = a_larger ? rb : ra;
        parent[child] = root;
        parity[child] = pa ^ pb ^ need;
        size[root] += size[child];
      }
    }
    i = j;
  }
  return true;
}

int PolyMesh::find_edge(int a, int b) const {
  if (a < 0 || b < 0 || a >= num_vertices_ || b >= num_vertices_) return -1;
  const int* c = vertex_corners(a);
  for (int i = 0, n = vertex_face_count(a); i < n; ++i) {
    int h = c[i];
    if (to_vertex(h) == b) return corner_edge_[h];
    int p = prev(h);  // incoming halfedge p: corner_vertex(p) -> a
    if (corner_vertex_[p] == b) return corner_edge_[p];
  }
  return -1;
}

PolyMesh PolyMesh::build(int num_vertices, const std::vector<int>& face_sizes,
                         const std::vector<int>& face_indices, Diagnostics* diagnostics) {
  PolyMesh m;
  const int nf = static_cast<int>(face_sizes.size());
  if (nf == 0 || num_vertices <= 0)
    fail(MeshErrorCode::EmptyMesh, ElementKind::None, -1, -1,
         "mesh is empty (" + std::to_string(num_vertices) + " vertices, " + std::to_string(nf) +
             " faces)");
  m.num_vertices_ = num_vertices;

  // Faces: sizes, index range, repeats.
  m.face_offsets_.assign(nf + 1, 0);
  for (int f = 0; f < nf; ++f) {
    if (face_sizes[f] < 3)
      fail(MeshErrorCode::FaceTooSmall, ElementKind::Face, f, -1,
           "face " + std::to_string(f) + " has " + std::to_string(face_sizes[f]) +
               " vertices; at least 3 are needed");
    m.face_offsets_[f + 1] = m.face_offsets_[f] + face_sizes[f];
  }
  const int nc = m.face_offsets_[nf];
  if (static_cast<size_t>(nc) != face_indices.size())
    fail(MeshErrorCode::IndexOutOfRange, ElementKind::Face, nf - 1, -1,
         "face sizes add up to " + std::to_string(nc) + " indices but " +
             std::to_string(face_indices.size()) + " were given");
  m.corner_vertex_.assign(face_indices.begin(), face_indices.end());
  m.corner_face_.resize(nc);
  for (int f = 0; f < nf; ++f) {
    const int b = m.face_offsets_[f], e = m.face_offsets_[f + 1];
    for (int h = b; h < e; ++h) {
      const int v = face_indices[h];
      m.corner_face_[h] = f;
      if (v < 0 || v >= num_vertices)
        fail(MeshErrorCode::IndexOutOfRange, ElementKind::Face, f, v,
             "face " + std::to_string(f) + " refers to vertex " + std::to_string(v) +
                 ", but the mesh has " + std::to_string(num_vertices) + " vertices");
      for (int g = b; g < h; ++g)
        if (face_indices[g] == v)
          fail(MeshErrorCode::RepeatedVertexInFace, ElementKind::Face, f, v,
               "face " + std::to_string(f) + " uses vertex " + std::to_string(v) + " twice");
    }
  }

  // Every face a quad (not only 4 corners per face on average: a triangle and a pentagon
  // have 8 corners too).
  m.quads_ = std::all_of(face_sizes.begin(), face_sizes.end(), [](int n) { return n == 4; });

  // Outgoing corners per vertex (unordered for now): counting sort.
  m.vertex_offsets_.assign(num_vertices + 1, 0);
  for (int h = 0; h < nc; ++h) ++m.vertex_offsets_[m.corner_vertex_[h] + 1];
  for (int v = 0; v < num_vertices; ++v) m.vertex_offsets_[v + 1] += m.vertex_offsets_[v];
  m.vertex_corners_.resize(nc);
  {
    Indices fill(m.vertex_offsets_.begin(), m.vertex_offsets_.end() - 1);
    for (int h = 0; h < nc; ++h) m.vertex_corners_[fill[m.corner_vertex_[h]]++] = h;
  }

  // Twins: halfedge a->b pairs with b->a. An undirected edge on more than two faces is
  // non-manifold; two halfedges a->b on one edge mean the faces disagree on orientation.
  m.twin_.assign(nc, -1);
  for (int h = 0; h < nc; ++h) {
    const int a = m.corner_vertex_[h], b = m.to_vertex(h);
    int same = 0, opposite = 0, other_same = -1, twin = -1;
    for (int i = m.vertex_offsets_[a]; i < m.vertex_offsets_[a + 1]; ++i) {
      int g = m.vertex_corners_[i];
      if (m.to_vertex(g) == b) {
        ++same;
        if (g != h) other_same = g;
      }
    }
    for (int i = m.vertex_offsets_[b]; i < m.vertex_offsets_[b + 1]; ++i) {
      int g = m.vertex_corners_[i];
      if (m.to_vertex(g) == a) {
        ++opposite;
        twin = g;
      }
    }
    if (same + opposite > 2)
      fail(MeshErrorCode::NonManifoldEdge, ElementKind::Edge, a, b,
           "non-manifold " + edge_name(a, b) + ": shared by " +
               std::to_string(same + opposite) + " faces (at most 2 allowed)");
    if (same > 1)
      fail(MeshErrorCode::InconsistentOrientation, ElementKind::Face, m.corner_face_[h],
           m.corner_face_[other_same],
           "faces " + std::to_string(m.corner_face_[h]) + " and " +
               std::to_string(m.corner_face_[other_same]) + " both traverse " + edge_name(a, b) +
               " in the same direction" +
               (faces_orientable(face_sizes, face_indices)
                    ? std::string(" (inconsistent orientation)")
                    : std::string(": the surface is not orientable (like a Moebius strip or a Klein bottle), so "
                                  "no reversal of faces mends it; it cannot be converted to a closed oriented "
                                  "body")));
    if (opposite == 1) m.twin_[h] = twin;
  }

  // Edges, numbered in order of first appearance.
  m.corner_edge_.assign(nc, -1);
  m.edge_corner_.reserve(nc / 2 + 8);
  for (int h = 0; h < nc; ++h) {
    if (m.corner_edge_[h] >= 0) continue;
    const int e = static_cast<int>(m.edge_corner_.size());
    m.edge_corner_.push_back(h);
    m.corner_edge_[h] = e;
    if (m.twin_[h] >= 0) m.corner_edge_[m.twin_[h]] = e;
  }

  // Order each vertex's corners as one fan: h -> twin(prev(h)).
  std::vector<int> ordered;
  for (int v = 0; v < num_vertices; ++v) {
    const int b = m.vertex_offsets_[v], e = m.vertex_offsets_[v + 1];
    if (b == e) {
      if (diagnostics)
        diagnostics->push_back({"unused-vertex", ElementKind::Vertex, v,
                                "vertex " + std::to_string(v) + " is not used by any face"});
      continue;
    }
    int start = m.vertex_corners_[b], boundary_starts = 0;
    for (int i = b; i < e; ++i)
      if (m.twin_[m.vertex_corners_[i]] < 0) {
        if (boundary_starts++ == 0) start = m.vertex_corners_[i];
      }
    ordered.clear();
    int h = start;
    do {
      ordered.push_back(h);
      h = m.twin_[m.prev(h)];
    } while (h >= 0 && h != start && static_cast<int>(ordered.size()) <= e - b);
    if (boundary_starts > 1 || static_cast<int>(ordered.size()) != e - b)
      fail(MeshErrorCode::NonManifoldVertex, ElementKind::Vertex, v, -1,
           "vertex " + std::to_string(v) +
               " is non-manifold: its faces do not form a single connected fan");
    std::copy(ordered.begin(), ordered.end(), m.vertex_corners_.begin() + b);
  }
  return m;
}

}  // namespace subd2nurbs
