// Quad recovery: a triangle mesh (FreeCAD's Mesh::Feature, glTF, STL-like sources) back to the
// quad-dominant cage it was triangulated from.
//
// Two triangles sharing an edge become one quad when the quad is convex, nearly planar and
// nearly rectangular. Candidates are scored (corner angles against 90 degrees, the fold across
// the removed diagonal) and taken greedily, best first, over the whole mesh, so a triangulated
// quad mesh gets its quads back whichever diagonal split them. Triangles around a fan vertex
// (an interior vertex all of whose faces are triangles, at least `fan_min_triangles` of them,
// none pairing into a good quad across a spoke) stay triangles: they are polar-structure
// candidates, and pairing them would make thin, badly shaped quads.
// Faces that are not triangles are kept as they are. Pure: no I/O.
#pragma once

#include <vector>

#include "core/mesh/mesh_input.h"

namespace subd2nurbs {

struct QuadRecoveryOptions {
  /// Largest |corner angle - 90| of an accepted quad, degrees.
  double max_corner_deviation_deg = 40.0;
  /// Largest angle between the two triangles' normals (the fold across the removed
  /// diagonal), degrees.
  double max_fold_deg = 40.0;
  /// Interior vertices with this many triangles or more (and only triangles) are fan
  /// candidates.
  int fan_min_triangles = 6;
  /// A fan candidate is kept as a fan when no pair of its triangles across a spoke scores
  /// at least this (1 = a rectangle, 0 = a corner deviation at the limit) ...
  double fan_max_spoke_quality = 0.5;
  /// ... and its longest spoke (edge at the vertex) is at most this times its shortest.
  double fan_max_spoke_ratio = 1.25;
};

struct QuadRecoveryResult {
  MeshInput mesh;  ///< the cage: recovered quads, kept triangles, other faces; tags carried over
  int input_triangles = 0;
  int quads = 0;                ///< quads made from two triangles
  int triangles_kept = 0;       ///< triangles left as they were (fans included)
  int fan_vertices = 0;         ///< fan vertices found
  int fan_triangles = 0;        ///< triangles kept because they belong to a fan
  int other_faces = 0;          ///< input faces with 4 or more sides, copied
  /// For each output face, the input faces it comes from (one, or two for a recovered quad).
  std::vector<std::vector<int>> sources;
};

/// Quality of the quad (p0, p1, p2, p3) made of triangles (p0, p1, p2) and (p0, p2, p3):
/// 1 - max |corner angle - 90| / max_corner_deviation, reduced by the fold; <= 0 when the
/// quad is rejected (not convex, too far from rectangular, folded too much, degenerate).
double quad_quality(const std::array<double, 3>& p0, const std::array<double, 3>& p1,
                    const std::array<double, 3>& p2, const std::array<double, 3>& p3,
                    const QuadRecoveryOptions& options = {});

/// Pairs triangles of `input` into quads (see the file comment). Creases on a removed
/// diagonal are dropped (a diagonal is not an edge of the cage); hole tags follow their faces
/// (a quad is a hole if either triangle was). Orientation is kept: a quad runs the same way
/// as its two triangles. Edges shared by more than two faces or by two faces of opposite
/// orientation are never removed.
QuadRecoveryResult recover_quads(const MeshInput& input, const QuadRecoveryOptions& options = {});

}  // namespace subd2nurbs
