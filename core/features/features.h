// Sharp features of a triangle (or polygon) mesh: dihedral-angle edges, open boundaries and
// user-tagged creases, grouped into chains between corners; short isolated chains dropped as
// noise. Used by the quad remesher (core/remesh) to align and constrain the cage.
#pragma once

#include <array>
#include <vector>

#include "core/mesh/mesh_input.h"

namespace subd2nurbs {

struct FeatureOptions {
  double angle_degrees = 30.0;   ///< an edge is sharp when the angle between its faces' normals exceeds this
  int min_chain_edges = 3;       ///< open feature chains with fewer edges, not touching other features or the boundary, are dropped as noise
  double corner_angle_degrees = 60.0;  ///< a chain vertex where the chain turns more than this is a corner
  /// Soft features: an edge whose dihedral angle exceeds soft_angle_degrees (but not
  /// angle_degrees) is sharp too when the bend is concentrated on it at the scale soft_reach
  /// (model units): no other edge within soft_reach of its midpoint, other than features and the
  /// edges continuing it along its line, bends by half its angle or more. (A tangent edge of a
  /// part, where a plane meets a surface at a small angle; not the facets of a coarse cylinder,
  /// whose neighbouring edges bend alike.) Grown along its line through edges above
  /// soft_angle_degrees. Off when either is 0 (quad_remesh sets soft_reach to its edge length).
  double soft_angle_degrees = 0.0;
  double soft_reach = 0.0;
  /// Fading creases: an open feature chain whose end touches no other feature is continued
  /// along its line (the straightest edge within 30 degrees) through edges below angle_degrees,
  /// as long as each bends the same way (convex or concave) by more than fade_angle_degrees and
  /// by less than the edge before it: a crease whose angle falls off, as where a
  /// fillet's surfaces become tangent. Reaching another feature curve, the chain joins it there;
  /// else its end is a dart (FeatureSet::darts), where the crease vanishes. Off when 0, or not
  /// below angle_degrees.
  double fade_angle_degrees = 1.0;
  /// Plane edges: where a planar region of the mesh ends at an edge bending by 1 degree or more,
  /// and the polygon beyond is at most a third as wide across the edge as the region and turns
  /// tighter than radius plane_radius (the bend at the edge over that width, doubled: a
  /// tessellated fillet's first facet meets the plane at half its facets' angle), that edge is a
  /// feature: the plane ends there, on a fillet too narrow for the cage to follow. The regions:
  /// per polygon its region (-1: none) and per region its width (2 area / perimeter), as
  /// set_plane_regions (core/remesh/quad_remesh.h) fills them. Off when empty or plane_radius is
  /// 0 (quad_remesh sets regions 0.3 h wide and 0.5 h: QuadRemeshOptions::plane_edges).
  std::vector<int> plane_of_polygon;
  std::vector<double> plane_widths;
  double plane_radius = 0.0;
};

struct FeatureSet {
  std::vector<std::array<int, 2>> edges;  ///< feature edges (vertex pairs, v0 < v1), sorted; boundary edges included
  std::vector<int> corners;               ///< vertices where the feature graph has degree != 2, or turns sharply; sorted
  int chains = 0;                         ///< feature curves (maximal chains between corners, or closed loops)
  int dropped_short_chains = 0;
  std::vector<int> darts;                 ///< the corners where a fading chain ends (fade_angle_degrees): its crease vanishes there; sorted
  int faded_edges = 0;                    ///< edges (in `edges`) added by continuing fading chains
  int plane_edges = 0;                    ///< edges (in `edges`) below the feature angle where a planar region ends (plane_radius)
};

/// Features of a triangle (or polygon) mesh. Polygons are fan-triangulated for the normals;
/// only the polygons' own edges can be features. Creases in mesh.creases with sharpness >=
/// kInfiniteSharpness are user-tagged features and always kept. The mesh must be manifold
/// (every edge on at most two faces); \throw Error(ErrorKind::Input) otherwise.
FeatureSet detect_features(const MeshInput& mesh, const FeatureOptions& options = {});

}  // namespace subd2nurbs
