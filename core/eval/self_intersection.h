// Self-intersection and overlap of the patches (issue 33): where the surface passes through
// itself (faces of one connected component crossing, e.g. catmark_rook's crenellations), and
// where separate components interpenetrate (catmark_car's parts) or one closed component lies
// inside another. The conversion is not refused: the report and the summary name the faces.
//
// How: every patch is tessellated on a grid whose lines follow its knots, with a step tied to
// the model size (adaptive: short knot spans merged, long ones split); a bounding volume
// hierarchy over all triangles gives the pairs whose boxes overlap; pairs that are neighbours
// (the same face's adjacent cells, cells of two faces touching the same part of a shared curve
// or a shared corner, welded vertices) are skipped; the others are tested edge against
// triangle. Each crossing found is then confirmed on the exact surfaces: Newton's method
// (minimum-norm steps) for a point S_a(u_a, v_a) = S_b(u_b, v_b), which must be transversal
// and, for a face with itself or a neighbour, not the trivial solution on the shared boundary.
// Triangles lying on each other in one plane are candidates too, and a tangent solution away
// from a shared boundary is kept as "touching" (sheets that touch or lie on each other, which
// OCCT's checker also flags) when the pair has no transversal crossing. A closed component with
// no crossing is tested for lying inside another closed one by ray parity. Pure; tolerances relative to the model size. docs/downstream.md.
#pragma once

#include <vector>

#include "core/nurbs/patch_set.h"

namespace subd2nurbs {

struct SelfIntersectionOptions {
  /// The tessellation step, relative to the model size: grid lines at most about this far
  /// apart (a span longer than that is split, shorter spans are merged).
  double step = 1.0 / 40;
  /// Most pieces one knot span is split into.
  int max_split = 16;
  /// Grid lines added towards an extraordinary corner of a face: at 2^-k of its domain, k = 1 ..
  /// corner_grading, fewer on a small face (its finest cells about 1e-4 of the model size).
  int corner_grading = 7;
  /// Only at corners shared by at most this many faces.
  int max_graded_valence = 8;
  /// Candidate triangle pairs tried on the exact surfaces per pair of faces.
  int candidates_per_pair = 4;
  /// Hubs: corners shared by more than this many faces (0: none). The triangles of a hub's faces
  /// are ordered by their angle around it, seen along its normal, and two groups whose angular
  /// ranges are apart are not compared (their projections are apart, so they cannot meet):
  /// without it the thin faces at a vertex of valence n give ~n^2 pairs of overlapping boxes.
  int hub_valence = 32;
};

/// Two faces whose surfaces cross (or, `inside`, a closed component inside another).
struct FaceCrossing {
  int face_a = -1, face_b = -1;            ///< PatchSet patch indices (B-rep faces); a crossing: face_a <= face_b
  int component_a = -1, component_b = -1;  ///< their components
  double ua = 0, va = 0, ub = 0, vb = 0;   ///< the witness's parameters on each face
  Point3 point{};                          ///< a point on both surfaces (the witness)
  double angle_deg = 0;                    ///< angle between the two surfaces there
  bool inside = false;  ///< component_a lies inside closed component_b (no crossing): point on face_a, face_b one of b's
  /// The surfaces meet tangentially there (angle below 0.06 deg), or on the edge of one of the
  /// faces (away from a boundary they share): sheets that touch or lie on each other (e.g. a
  /// flat cage folded over, two boxes side by side) without crossing.
  bool touching = false;
};

struct SelfIntersectionReport {
  int components = 0;            ///< connected components of the faces (by shared curves)
  std::vector<int> component;    ///< per face
  long long triangles = 0;       ///< of the tessellation
  long long candidate_pairs = 0; ///< triangle pairs that crossed, before the exact check
  long long tested_pairs = 0;    ///< triangle pairs whose boxes overlap, tested for a crossing
  int hubs = 0;                  ///< corners treated as hubs (SelfIntersectionOptions::hub_valence)
  /// Pairs of faces of one component whose surfaces cross or touch, one witness per pair (a
  /// crossing when there is one), sorted.
  std::vector<FaceCrossing> self;
  /// Pairs of faces of different components that cross or touch, and closed components inside
  /// others.
  std::vector<FaceCrossing> overlaps;
  /// Pairs of components that overlap (cross or contain), sorted, a < b.
  std::vector<std::pair<int, int>> overlapping_components;
  bool empty() const { return self.empty() && overlaps.empty(); }
  /// Witnesses in `list` that touch (FaceCrossing::touching), the rest cross or contain.
  static long long touching_count(const std::vector<FaceCrossing>& list) {
    long long n = 0;
    for (const FaceCrossing& c : list) n += c.touching;
    return n;
  }
};

/// Finds where the patches cross themselves or each other. Cost: about the tessellation's
/// triangles (O(n log n)) plus a Newton solve per candidate face pair.
SelfIntersectionReport find_self_intersections(const PatchSet& ps, const SelfIntersectionOptions& options = {});

}  // namespace subd2nurbs
