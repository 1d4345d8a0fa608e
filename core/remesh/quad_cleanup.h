// Clean-up of a quad-dominant mesh (quads and triangles) towards regular valences (issue #28):
// the quad remesher's coarse mesh after pairing, before its split into an all-quad cage. Edge
// rotations inside the union of two faces (two quads: a hexagon re-split; a quad and a triangle:
// a pentagon re-split, which moves the triangle), triangle walks (a few such rotations carrying a
// triangle until it meets another, then the two merged into a quad), each kept only when the
// split cage's summed valence excess drops. docs/remesh.md step 6b describes the pass.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <vector>

namespace subd2nurbs {

struct QuadCleanupOptions {
  double min_corner_sine = 0.2;     ///< every new face: the smallest corner sine (convex, not degenerate)
  double keep_sine = 0.3;           ///< ... and at least min(keep_sine, the replaced faces' smallest corner sine)
  double curve_sine = 0.9;          ///< ... at vertices on feature curves or the boundary: min(curve_sine, the replaced faces' smallest there)
  double max_normal_degrees = 60;   ///< every new face within this of the old faces' normal and of its corners' normals
  int walk_depth = 3;               ///< rotations a triangle may make to meet another (0: no walks)
  int max_passes = 20;
};

struct QuadCleanupStats {
  int rotations = 0;  ///< edge rotations kept (each re-splits the union of two faces)
  int merges = 0;     ///< pairs of triangles merged into quads (at the end of a walk)
  int walks = 0;      ///< triangle walks kept (one or more rotations, maybe a merge)
  /// The all-quad split's (every polygon into quads around its centre) summed valence excess
  /// (|valence - 4| inside, |valence - 3| on the boundary, corners free, plus |size - 4| per
  /// polygon for its centre) and its irregular vertices, before and after.
  int excess_before = 0, excess_after = 0, irregular_before = 0, irregular_after = 0;
};

/// Cleans `polygons` (consistently oriented, manifold; vertices index `positions`) in place:
/// the vertex set, the boundary and every feature edge (is_feature(a, b)) stay as they are, only
/// interior non-feature edges are rotated or removed (two triangles into a quad), so the Euler
/// characteristic and the boundary loops are kept. `normals`: the surface normal per vertex
/// (unit). `corner`: per vertex, 1 = its valence is free (a feature corner). Deterministic.
QuadCleanupStats clean_quad_dominant(std::vector<std::vector<int>>& polygons,
                                     const std::vector<Eigen::Vector3d>& positions,
                                     const std::vector<Eigen::Vector3d>& normals, const std::vector<char>& corner,
                                     const std::function<bool(int, int)>& is_feature,
                                     const QuadCleanupOptions& options = {});

}  // namespace subd2nurbs
