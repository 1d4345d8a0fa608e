// Wide sectors at the corners of a cage (docs/math.md "Concave corners"). At a corner (a vertex
// tagged infinitely sharp, or where three or more infinitely sharp or boundary edges meet) the
// Catmull-Clark corner rule makes the limit tangent along each edge between two sharp edges a
// positive combination of the two sharp edges' tangents, so a sector (the faces between two
// consecutive sharp or boundary edges around the corner) can only cover the convex wedge between
// them: a sector wider than 180 degrees (an L-shaped plane's inner corner) is folded over itself
// at the corner. The remesher splits the flat ones by a crease; the cage path warns of them.
#pragma once

#include <vector>

#include "core/mesh/mesh_input.h"

namespace subd2nurbs {

struct CornerSector {
  int corner = -1;       ///< the vertex
  double degrees = 0;    ///< the sum of the sector's faces' angles at the corner, on the cage
  int faces = 0;         ///< faces in the sector
  bool flat = false;     ///< its faces' normals all within 5 degrees of their mean
  /// The far vertex of the edge inside the sector nearest its middle whose far vertex is on no
  /// sharp edge and no corner (-1: none, e.g. a sector of one face)
  int middle = -1;
};

/// The sectors wider than `min_degrees` at the corners of `cage` (a valid cage: manifold,
/// oriented; hole faces count as missing), in vertex order, each corner's sectors from its
/// sharp edges in vertex order. Deterministic.
std::vector<CornerSector> wide_corner_sectors(const MeshInput& cage, double min_degrees);

}  // namespace subd2nurbs
