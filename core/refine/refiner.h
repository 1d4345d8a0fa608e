// Uniform Catmull-Clark refinement with OpenSubdiv's boundary, crease and corner rules.
//
// A SubdivLevel is the topology of one level plus its tags (sharpness, holes). Refining it
// gives the child level and the stencil table that maps the parent's vertices to the
// child's. Child vertices are numbered: first one per parent vertex (same order), then one
// per parent face, then one per parent edge. Child faces are quads, one per parent corner h
// (face index = h), with vertices (vertex-child of corner_vertex(h), edge-child of
// corner_edge(h), face-child of corner_face(h), edge-child of corner_edge(prev(h))).
#pragma once

#include <vector>

#include "core/mesh/mesh_input.h"
#include "core/mesh/poly_mesh.h"
#include "core/refine/stencil_table.h"

namespace subd2nurbs {

// Sharpness is stored as float, exactly as OpenSubdiv stores it: the decay (s - 1, Chaikin
// averaging) and the fractional blend weights are computed in float there, and matching its
// refinement to 1e-12 needs the same rounding. All point weights are double.
struct SubdivLevel {
  PolyMesh mesh;
  std::vector<float> edge_sharpness;     ///< per edge; boundary edges are infinitely sharp
  std::vector<float> vertex_sharpness;   ///< per vertex
  std::vector<char> face_hole;           ///< per face: 1 if the face produces no surface
  SubdivOptions options;

  /// Validates the input and applies the base-level tagging (boundary edges infinitely sharp,
  /// corners sharpened for BoundaryRule::EdgeAndCorner, boundary faces made holes for
  /// BoundaryRule::None). \throw InvalidMeshError
  static SubdivLevel from_input(const MeshInput& input, Diagnostics* diagnostics = nullptr);
  /// The tagging alone, for an input validated already: `mesh` is validate_and_build(input)
  /// (core/mesh/validate.h), e.g. from io's validate_cage, which names the file line of a problem.
  static SubdivLevel from_validated(PolyMesh mesh, const MeshInput& input);

  /// Largest finite (semi-sharp) sharpness on any edge or vertex, 0 if none.
  double max_semi_sharpness() const;
  /// True if edge e is infinitely sharp: tagged so, or a boundary edge of this mesh (tagged so
  /// on a level, untagged on a local piece cut out of one).
  bool infinitely_sharp(int e) const {
    return mesh.is_boundary_edge(e) || edge_sharpness[e] >= kInfiniteSharpness;
  }
};

/// True if base-level tagging (SubdivLevel::from_input) makes v infinitely sharp by itself,
/// whatever its tags: unused vertices, and topological corners under
/// BoundaryRule::EdgeAndCorner. A written cage needs no corner tag for such a vertex.
bool is_sharpened_by_tagging(const PolyMesh& mesh, BoundaryRule rule, int v);

/// Subdivision rule of a vertex (OpenSubdiv `Sdc::Crease::Rule`): from its sharpness and the
/// number of sharp incident edges (0 smooth, 1 dart, 2 crease, more corner; any vertex
/// sharpness makes it a corner).
enum class VertexRule : unsigned char { Smooth, Dart, Crease, Corner };
VertexRule vertex_rule(const SubdivLevel& level, int v);

/// Calls fn(edge, other_vertex) for every edge incident to v, in fan order.
template <class Fn>
void for_each_vertex_edge(const PolyMesh& m, int v, Fn&& fn) {
  const int* c = m.vertex_corners(v);
  const int n = m.vertex_face_count(v);
  for (int i = 0; i < n; ++i) fn(m.corner_edge(c[i]), m.to_vertex(c[i]));
  if (n > 0 && m.is_boundary_vertex(v)) {
    int p = m.prev(c[n - 1]);  // incoming boundary halfedge of the last face
    fn(m.corner_edge(p), m.corner_vertex(p));
  }
}

/// Where a child vertex comes from.
enum class ChildOrigin : unsigned char { Vertex = 0, Face = 1, Edge = 2 };

struct RefinementStep {
  SubdivLevel child;
  StencilTable stencils;  ///< parent vertices -> child vertices
};

/// One uniform Catmull-Clark step.
RefinementStep refine_once(const SubdivLevel& parent);

/// Uniform refinement to `levels` levels. levels[0] is the base; steps[k] maps level k to k+1.
struct Refinement {
  std::vector<SubdivLevel> levels;
  std::vector<StencilTable> steps;

  /// Stencils from base vertices to the vertices of level k (composition of the steps).
  StencilTable stencils_from_base(int k) const;
  /// Positions of every level, given base positions.
  std::vector<std::vector<Point3>> positions(const std::vector<Point3>& base) const;
};
Refinement refine_uniform(const SubdivLevel& base, int levels);

/// Child vertex index layout helpers (see the file comment).
inline int child_of_vertex(const PolyMesh&, int v) { return v; }
inline int child_of_face(const PolyMesh& m, int f) { return m.num_vertices() + f; }
inline int child_of_edge(const PolyMesh& m, int e) { return m.num_vertices() + m.num_faces() + e; }

/// Stencils giving the limit position of each vertex of `level` (Catmull-Clark limit masks:
/// smooth, crease, corner). Rows are over the level's own vertices. Where no closed form exists
/// (n-gons, semi-sharp features still active) the level is refined and the vertex-child's
/// limit is used: ceil(max semi-sharpness) + 1 uniform levels of the whole mesh, so very sharp
/// semi-sharp creases are expensive (a localised version is future work).
/// Darts (one sharp edge) and smooth valence-2 vertices have no closed-form mask; their exact
/// limit weights are computed as the left eigenvector (eigenvalue 1) of the local subdivision
/// matrix. OpenSubdiv uses approximations there (smooth mask; the vertex itself).
StencilTable limit_stencils(const SubdivLevel& level);

/// Limit weights of an interior vertex of valence n surrounded by quads, ordered
/// (v, e_0..e_{n-1}, d_0..d_{n-1}) in fan order, where edge `sharp_edge` (index into e, or -1)
/// is infinitely sharp: the normalised left eigenvector of the 1-ring subdivision matrix
/// (solved for; in closed form for a smooth vertex, sharp_edge -1, above kDenseValence).
std::vector<double> ring_limit_weights(int n, int sharp_edge);

/// Up to this valence the eigen-structure at an extraordinary vertex (ring_limit_weights, the
/// Stam decomposition of core/limit/stam_eigen.h) is computed with dense O(n^3) solves and
/// products; above it in O(n^2) (closed forms, sparse products, block-wise inverses), the same
/// to rounding.
constexpr int kDenseValence = 64;

}  // namespace subd2nurbs
