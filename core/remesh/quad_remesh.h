// Field-aligned all-quad remeshing of a triangle mesh (issue #28): a 4-RoSy cross field
// smoothed over the mesh and constrained to the feature curves (and pulled towards principal
// curvature directions), a position field (lattice offsets), then an extraction by edge
// collapses that keeps the topology by construction (link condition), pairing into quads and one
// Catmull-Clark-style split into an all-quad cage. docs/remesh.md describes the method.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <functional>

#include "core/features/features.h"
#include "core/mesh/mesh_input.h"

namespace subd2nurbs {

struct QuadRemeshOptions {
  int target_faces = 0;     ///< wanted quad count (approximate); used when > 0
  double edge_length = 0;   ///< wanted edge length in model units; used when > 0 and target_faces == 0
                            ///< (exactly one of them must be > 0, else Error(ErrorKind::Settings))
  FeatureOptions features;
  double curvature_alignment = 1.0;  ///< weight of principal-curvature alignment of the cross field (0 = off)
  int smoothing_iterations = 0;      ///< 0 = automatic
  bool regularize_valence = true;    ///< edge flips on the coarse triangles before pairing (fewer extraordinary vertices)
  bool cleanup = true;  ///< quad-dominant clean-up of the coarse quads and triangles before the split (core/remesh/quad_cleanup.h)
  bool relocate_stuck = true;  ///< move coarse vertices stuck beside a feature curve away from it before the split (docs/remesh.md step 6c)
  bool align_tight_loops = true;  ///< concentric closed feature loops tighter than the lattice (a hole's rims) keep the same coarse vertices, one above the other (docs/remesh.md step 4)
  bool pin_tight_arcs = true;  ///< position field: lattice columns at the ends of feature arcs tighter than the lattice (docs/remesh.md step 3)
  bool cancel_dislocations = false;  ///< position field: cancel its dislocations in pairs away from features, and merge the knots the extraction leaves (docs/remesh.md step 3b; off: mixed on the CAD parts)
  /// With target_faces: the size check aims the cage's faces at the target (docs/remesh.md step 7:
  /// up to 5 runs of the position field and the extraction, the spacing corrected each time,
  /// until the faces are within 0.9 .. 1.0 x target; the run nearest that band is kept). Off by
  /// default: the older, cheaper rule (one more run only above 1.3 x target) keeps the cages the
  /// mesh path's quality tests were measured on (on, a drilled box's rims and an acute tip at
  /// --target-faces 300 come out worse: docs/remesh.md step 7).
  bool aim_at_target = false;
  /// With edge_length: one extraction at exactly that spacing (2 x edge_length before the split),
  /// without the size check's second run when the faces exceed area / edge_length^2 by 30 %
  /// (docs/remesh.md step 7). The faces then carry the lattice's irregularities (up to 2 x area /
  /// edge_length^2 at coarse sizes: the drilled cube of QuadRemesh.ExactSpacingKeepsTheEdgeLength),
  /// but the edges have the length asked for, and a change of the extraction can be compared at
  /// one lattice (without a second run's new draw).
  bool exact_spacing = false;
  /// Soft features (FeatureOptions::soft_angle_degrees): edges bending by more than this fraction
  /// of the feature angle, with the bend concentrated within the cage's edge length, are
  /// features too (used when features.soft_angle_degrees and soft_reach are 0; 0 = off).
  double soft_features = 0.5;
  /// Plane edges (FeatureOptions::plane_of_polygon, plane_radius): a planar region at least
  /// 0.3 h wide ends in a feature where the surface beyond bends tighter than radius 0.5 h (h
  /// the edge length), a fillet the cage's quads cannot follow (used when features has no
  /// regions and no radius; docs/remesh.md "Plane edges").
  bool plane_edges = true;
  /// Concave corners: a flat corner sector spanning more than 170 degrees (an L-shaped plane's
  /// inner corner), which the corner rule folds over itself, is split in two by tagging its
  /// middle edge infinitely sharp (docs/remesh.md step 9).
  bool split_concave_sectors = true;
  /// Coarse triangles lying along a feature chain (an angle below 15 degrees at a feature vertex
  /// between a feature edge and another) flipped open before the pairing (docs/remesh.md step 5).
  bool flip_chain_slivers = true;
  /// Caps: coarse triangles with an angle above 160 degrees (a vertex almost on the opposite
  /// edge) flipped before the pairing, feature edges kept (docs/remesh.md step 5).
  bool flip_caps = true;
};

struct QuadRemeshStats {
  int input_vertices = 0, input_faces = 0;
  int faces = 0, vertices = 0, extraordinary_vertices = 0;  ///< of the cage (interior valence != 4, boundary valence != 3, excluding feature corners which count separately)
  int feature_edges = 0;  ///< cage edges tagged infinitely sharp
  int feature_chains_in = 0, feature_chains_kept = 0, corners = 0;
  int euler_input = 0, euler_cage = 0, boundaries_input = 0, boundaries_cage = 0, components_input = 0,
      components_cage = 0;
  /// The cross field's singularities on the dense mesh (its triangles around which the field turns
  /// by a quarter turn or more, Instant Meshes' index): each is an extraordinary vertex the field
  /// asks for; the cage's others are made by the extraction (docs/remesh.md step 2).
  int field_singularities = 0;
  /// Their indices summed, in quarter turns (+1: a valence-3 singularity, -1: valence 5). On a
  /// closed mesh 4 x its Euler characteristic (Poincare-Hopf: the test QuadRemesh.FieldSingularitiesSumToEuler).
  int field_index_sum = 0;
  double field_seconds = 0, extract_seconds = 0;  ///< wall time per stage
  /// Threads the fields' sweeps on the dense mesh ran on (the conversion's threads, 1 where the
  /// mesh's vertex order leaves too little to share; the cage is the same either way:
  /// core/util/wave_sweeps.h, docs/remesh.md "Threads").
  int field_threads = 1;
  int dense_vertices = 0;      ///< vertices of the input after long edges were split (the fields' domain)
  int coarse_triangles = 0;    ///< triangles left unpaired after the extraction (each becomes 3 quads)
  int coarse_quads = 0;        ///< quads paired by the extraction (each becomes 4 quads)
  int flips = 0;               ///< coarse edges flipped towards regular valences (regularize_valence)
  int cleanup_rotations = 0;   ///< coarse edges rotated by the clean-up (cleanup)
  int cleanup_merges = 0;      ///< pairs of coarse triangles merged into quads by the clean-up
  int relocations = 0;         ///< coarse vertices stuck beside a feature curve moved away from it (relocate_stuck)
  int tight_loops = 0;         ///< closed feature loops tighter than the lattice whose coarse vertices were aligned with concentric ones (align_tight_loops)
  int arc_pins = 0;            ///< chain vertices whose lattice point the position field kept at themselves (pin_tight_arcs)
  int position_dislocations = 0;       ///< dense triangles around which the lattice translations do not sum to zero (cancel_dislocations; before)
  int position_dislocations_left = 0;  ///< ... and after the cancelling (those near features are left alone)
  double cleanup_seconds = 0;  ///< wall time of the clean-up (part of extract_seconds)
  int attempts = 0;            ///< position field + extraction runs (the size check, docs/remesh.md step 7)
  double spacing = 0;          ///< the kept run's lattice spacing (model units; the split halves it: the cage's edges are about spacing / 2)
  int concave_sectors = 0;     ///< corner sectors split by a crease edge (split_concave_sectors)
  int sliver_flips = 0;        ///< coarse slivers along a feature chain flipped open (flip_chain_slivers)
  int cap_flips = 0;           ///< coarse caps (an angle above 160 degrees) flipped (flip_caps)
};

struct QuadRemeshResult {
  MeshInput cage;       ///< all quads, manifold, consistently oriented like the input; feature edges as CreaseTag
                        ///< {v0,v1,kInfiniteSharpness}; feature corners as CornerTag {v, kInfiniteSharpness};
                        ///< positions on (near) the input surface
  FeatureSet features;  ///< the input's features
  QuadRemeshStats stats;
  /// The edges tagged to split concave sectors (split_concave_sectors; in cage.creases too, not
  /// features of the mesh: the feature counts and measures leave them out).
  std::vector<std::array<int, 2>> sector_edges;
  bool cancelled = false;  ///< the progress callback returned false: the cage is empty (as ShapeFitStop::Cancelled)
};

/// FeatureOptions' planar regions of `mesh` for plane edges: detect_planar_regions
/// (core/fit/planar_regions.h) over its polygons' fan triangles, regions at least `min_width`
/// wide; a polygon is in a region when all its triangles are.
void set_plane_regions(const MeshInput& mesh, double min_width, FeatureOptions& options);

/// progress(fraction in [0,1]) -> false cancels: the result then has cancelled = true and an
/// empty cage (the project's convention, as fit_to_shape's ShapeFitStop::Cancelled).
/// \throw Error(ErrorKind::Settings) for sizes that are not exactly one positive value,
/// Error(ErrorKind::Input) for a mesh that is not manifold / oriented or has no faces,
/// Error(ErrorKind::Fit) if the cage could not be made with the input's topology.
QuadRemeshResult quad_remesh(const MeshInput& mesh, const QuadRemeshOptions& options,
                             const std::function<bool(double)>& progress = {});

namespace remesh_detail {
/// std::round (halves away from zero) without libm's call and without a branch on the fraction
/// (its direction is a coin toss in the field sweeps, which round four times per neighbour): the
/// same value for every double (test: RemeshRounding.*).
inline double round_half_away(double x) {
  if (!(std::abs(x) < 4503599627370496.0)) return x;  // 2^52: an integer already (or inf / NaN)
  std::int64_t i = static_cast<std::int64_t>(x);  // towards zero
  const double f = x - static_cast<double>(i);     // exact
  i += static_cast<std::int64_t>(f >= 0.5) - static_cast<std::int64_t>(f <= -0.5);
  return std::copysign(static_cast<double>(i), x);
}
}  // namespace remesh_detail

}  // namespace subd2nurbs
