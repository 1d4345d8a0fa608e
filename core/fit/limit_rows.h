// The limit-position operator L of a cage: row v gives the exact limit position of vertex v as
// a weighted sum of the cage's vertices (docs/fitting.md). Interpolation solves L P = c.
//
// * Catmull-Clark vertices: the limit masks of core/refine/limit.cpp (smooth, crease, corner,
//   boundary; darts and smooth valence-2 vertices by their exact left eigenvector; n-gons
//   after one step).
// * Semi-sharp tags: the limit of a vertex is the limit of its vertex-child, and the child's
//   limit depends only on the faces around the vertex. So the fan of faces at v is cut out,
//   refined one level, the child's fan cut out again, and so on until no semi-sharp edge or
//   vertex tag is left at v; then the closed-form mask applies. The cost is a few tiny
//   refinements per vertex, whatever the sharpness (the global version in limit_stencils
//   refines the whole cage ceil(s) + 1 times).
// * Polar structures (when given): the BP limit (docs/fitting.md):
//   pole (p0 + m) / 2, ring-1 and ring-2 vertices the tensor bicubic limit of their
//   vertex-children after two radial BP steps.
// Vertices without limit surface (unused, or every incident face a hole) get the identity row
// and are listed in `no_surface`.
#pragma once

#include <vector>

#include "core/polar/polar_structure.h"
#include "core/refine/refiner.h"

namespace subd2nurbs {

struct LimitRows {
  StencilTable rows;            ///< one row per vertex, over the level's vertices
  std::vector<int> no_surface;  ///< vertices given the identity row
  std::vector<int> polar_rows;  ///< vertices whose row is BP's (poles, rings 1 and 2)
  int local_rows = 0;           ///< rows computed by the local fan refinement (semi-sharp)
};

/// The limit operator of `level`. `polar`: structures (from detect_polar_structures on the
/// same level) whose pole, ring-1 and ring-2 rows are BP's; nullptr or empty: Catmull-Clark
/// everywhere.
LimitRows limit_rows(const SubdivLevel& level, const std::vector<PolarStructure>* polar = nullptr);

/// The exact limit row of one vertex by local refinement of its fan (see the file comment).
/// Returned as (vertex, weight) pairs over the level's vertices (duplicates merged).
std::vector<std::pair<int, double>> local_limit_row(const SubdivLevel& level, int v);

/// BP limit rows of one structure: for its pole, then ring1[0..n-1], then ring2[0..n-1], each
/// as (vertex, weight) pairs over the structure's rings 0..3.
std::vector<std::vector<std::pair<int, double>>> bp_limit_rows(const PolarStructure& s);

}  // namespace subd2nurbs
