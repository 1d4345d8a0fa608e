// PolyMesh: halfedge connectivity of a polygon cage. No coordinates (topology decides,
// geometry follows). Faces are stored as one flat list of "corners"; corner h of face f is
// also the halfedge leaving corner_vertex(h) along f's boundary, so a halfedge needs no
// storage of its own beyond twin / edge / face.
#pragma once

#include <vector>

#include "core/mesh/errors.h"
#include "core/util/default_init_vector.h"

namespace subd2nurbs {

/// Whether the faces can be oriented consistently: false for a Moebius strip or a Klein bottle
/// (some cycle of faces meets itself reversed), true if reversing some faces would mend every
/// edge that two faces traverse the same way. Faces given as for PolyMesh::build (sizes >= 3,
/// indices in range); an edge on more than two faces counts each pair.
bool faces_orientable(const std::vector<int>& face_sizes, const std::vector<int>& face_indices);

class PolyMesh {
 public:
  PolyMesh() = default;

  /// Builds connectivity from a face list and validates the topology: face size >= 3,
  /// indices in range and not repeated within a face, every edge on at most two faces,
  /// consistent orientation, every vertex's faces forming one fan.
  /// \throw InvalidMeshError naming the first offending element.
  /// Unused vertices are reported in `diagnostics` (if given), not rejected.
  static PolyMesh build(int num_vertices, const std::vector<int>& face_sizes,
                        const std::vector<int>& face_indices, Diagnostics* diagnostics = nullptr);

  int num_vertices() const { return num_vertices_; }
  int num_faces() const { return static_cast<int>(face_offsets_.size()) - 1; }
  int num_edges() const { return static_cast<int>(edge_corner_.size()); }
  int num_corners() const { return static_cast<int>(corner_vertex_.size()); }

  // --- faces --------------------------------------------------------------------------
  int face_begin(int f) const { return face_offsets_[f]; }
  int face_end(int f) const { return face_offsets_[f + 1]; }
  int face_size(int f) const { return face_offsets_[f + 1] - face_offsets_[f]; }
  const int* face_vertices(int f) const { return corner_vertex_.data() + face_offsets_[f]; }
  bool all_quads() const { return quads_; }

  // --- corners = halfedges ------------------------------------------------------------
  /// Halfedge h runs from corner_vertex(h) to corner_vertex(next(h)) inside corner_face(h).
  int corner_vertex(int h) const { return corner_vertex_[h]; }
  int corner_face(int h) const { return quads_ ? h >> 2 : corner_face_[h]; }
  int corner_edge(int h) const { return corner_edge_[h]; }
  /// The opposite halfedge in the neighbouring face, or -1 on the boundary.
  int twin(int h) const { return twin_[h]; }
  int next(int h) const {
    if (quads_) return (h & ~3) | ((h + 1) & 3);
    int f = corner_face_[h];
    return h + 1 == face_offsets_[f + 1] ? face_offsets_[f] : h + 1;
  }
  int prev(int h) const {
    if (quads_) return (h & ~3) | ((h + 3) & 3);
    int f = corner_face_[h];
    return h == face_offsets_[f] ? face_offsets_[f + 1] - 1 : h - 1;
  }
  int to_vertex(int h) const { return corner_vertex_[next(h)]; }

  // --- edges --------------------------------------------------------------------------
  /// A halfedge of edge e; for a boundary edge, its only one.
  int edge_corner(int e) const { return edge_corner_[e]; }
  int edge_vertex(int e, int end) const {
    int h = edge_corner_[e];
    return end == 0 ? corner_vertex_[h] : to_vertex(h);
  }
  bool is_boundary_edge(int e) const { return twin_[edge_corner_[e]] < 0; }
  /// Edge joining a and b, or -1.
  int find_edge(int a, int b) const;

  // --- vertices -----------------------------------------------------------------------
  /// Corners at v (one per incident face) in fan order: each next corner is
  /// twin(prev(previous corner)), i.e. counter-clockwise seen from outside. A boundary
  /// vertex's fan starts at the corner whose outgoing halfedge is on the boundary.
  const int* vertex_corners(int v) const { return vertex_corners_.data() + vertex_offsets_[v]; }
  int vertex_face_count(int v) const { return vertex_offsets_[v + 1] - vertex_offsets_[v]; }
  bool is_boundary_vertex(int v) const {
    return vertex_face_count(v) > 0 && twin_[vertex_corners(v)[0]] < 0;
  }
  /// Number of incident edges.
  int valence(int v) const { return vertex_face_count(v) + (is_boundary_vertex(v) ? 1 : 0); }
  bool is_unused_vertex(int v) const { return vertex_face_count(v) == 0; }
  /// A boundary vertex with exactly one incident face (two boundary edges).
  bool is_topological_corner(int v) const { return is_boundary_vertex(v) && vertex_face_count(v) == 1; }

 private:
  friend class PolyMeshAssembler;

  using Indices = DefaultInitVector<int>;
  int num_vertices_ = 0;
  bool quads_ = false;            ///< every face is a quad: corner h is in face h / 4
  Indices face_offsets_{0};
  Indices corner_vertex_;
  Indices corner_face_;           ///< empty when quads_ (derived from the corner index)
  Indices corner_edge_;
  Indices twin_;
  Indices edge_corner_;
  Indices vertex_offsets_{0};
  Indices vertex_corners_;
};

/// Low-level access for code that constructs a PolyMesh directly from known connectivity
/// (the refiner builds a child mesh from its parent without searching for twins).
class PolyMeshAssembler {
 public:
  using Indices = PolyMesh::Indices;
  static int& num_vertices(PolyMesh& m) { return m.num_vertices_; }
  /// Declares every face a quad; corner_face is then derived and need not be filled.
  static bool& all_quads(PolyMesh& m) { return m.quads_; }
  static Indices& face_offsets(PolyMesh& m) { return m.face_offsets_; }
  static Indices& corner_vertex(PolyMesh& m) { return m.corner_vertex_; }
  static Indices& corner_face(PolyMesh& m) { return m.corner_face_; }
  static Indices& corner_edge(PolyMesh& m) { return m.corner_edge_; }
  static Indices& twin(PolyMesh& m) { return m.twin_; }
  static Indices& edge_corner(PolyMesh& m) { return m.edge_corner_; }
  static Indices& vertex_offsets(PolyMesh& m) { return m.vertex_offsets_; }
  static Indices& vertex_corners(PolyMesh& m) { return m.vertex_corners_; }
};

}  // namespace subd2nurbs
