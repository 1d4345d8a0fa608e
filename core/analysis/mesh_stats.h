// Descriptive statistics of a cage or refined level (for `subd2nurbs info` and reports).
// Pure: no I/O.
#pragma once

#include <map>
#include <vector>

#include "core/refine/refiner.h"
#include "core/util/point3.h"

namespace subd2nurbs {

struct BoundingBox {
  Point3 min{0, 0, 0};
  Point3 max{0, 0, 0};
  double diagonal = 0;  ///< length of max - min
};

struct MeshStats {
  // Element counts. `corners` are face-vertex incidences (the sum of all face sizes).
  int vertices = 0, faces = 0, edges = 0, corners = 0;
  std::map<int, int> face_sizes;  ///< face size -> number of faces
  std::map<int, int> valences;    ///< valence (incident edges) -> number of used vertices

  // Boundary. A boundary loop is a closed chain of boundary edges.
  int boundary_edges = 0, boundary_vertices = 0, boundary_loops = 0;

  // Tags as they are in effect on this level. Boundary edges are excluded from the crease
  // counts (they are always infinitely sharp).
  int infinite_crease_edges = 0;    ///< interior edges with sharpness >= kInfiniteSharpness
  int semi_sharp_crease_edges = 0;  ///< interior edges with 0 < sharpness < kInfiniteSharpness
  /// Vertices with sharpness > 0, except those sharpened automatically (topological corners
  /// under BoundaryRule::EdgeAndCorner, unused vertices): the vertices that carry a corner tag.
  int corner_vertices = 0;
  /// Boundary vertices with a single face (sharp corners under EdgeAndCorner).
  int topological_corners = 0;
  int holes = 0;  ///< faces that produce no surface

  /// Used vertices with a non-regular valence for a quad mesh: interior vertices with
  /// valence != 4 and boundary vertices with valence != 3, not counting topological corners
  /// (valence 2 with one face, regular on a boundary).
  int extraordinary_vertices = 0;
  int unused_vertices = 0;  ///< vertices no face refers to

  int components = 0;  ///< edge-connected groups of faces
  /// V - E + F over the used vertices (hole faces count as faces). 2 for a closed sphere-like
  /// component, 2 - 2g for genus g; each boundary loop lowers it by one.
  int euler_characteristic = 0;
  bool closed = false;  ///< no boundary edges

  BoundingBox bounds;  ///< over the used vertices
};

/// Statistics of `level` with vertex positions `positions` (one per vertex of level.mesh).
/// \throw std::invalid_argument if the sizes do not match.
MeshStats compute_stats(const SubdivLevel& level, const std::vector<Point3>& positions);

/// True if the vertex is infinitely sharp only because base-level tagging made it so
/// (is_sharpened_by_tagging), so that no corner tag is needed to reproduce its sharpness.
bool is_automatic_corner(const SubdivLevel& level, int v);

}  // namespace subd2nurbs
