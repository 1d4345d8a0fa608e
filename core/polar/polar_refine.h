// Refinement of a cage with polar structures: the combined 4-step procedure of
// Myles-Karciauskas-Peters 2008, section 2 (docs/math.md 3.6).
//
//   1. Split: each polar structure (rings 0..3) is copied out.
//   2. Each structure gets k radial BP steps (saved: BP always continues from the radial-only
//      net), then k circular steps, so its rings have n 2^k points like Catmull-Clark's.
//   3. The cage gets k Catmull-Clark steps. Level-k points on rings >= 2^(k+1) - 1 of a
//      structure do not depend on its pole, so they are the Catmull-Clark side of the paper's
//      split mesh (the pole's own region is simply discarded).
//   4. Merge: inside level-k ring 2^k the Catmull-Clark faces are replaced by the BP pole,
//      its n 2^k triangles and BP rings 1 .. 2^k - 1; rings 2^k .. 2^(k+1) - 2 take BP's
//      positions; from ring 2^(k+1) - 1 on, BP and Catmull-Clark are identical (the overlap,
//      measured in PolarRefinement::max_overlap_difference).
#pragma once

#include <vector>

#include "core/polar/polar_structure.h"
#include "core/refine/refiner.h"

namespace subd2nurbs {

struct PolarRefinement {
  SubdivLevel level;             ///< the merged level-k mesh, with Catmull-Clark's tags
  std::vector<Point3> positions;
  int structures = 0;            ///< polar structures refined by BP
  /// Largest |BP - Catmull-Clark| over the overlap rings 2^(k+1) - 1 .. 2^(k+1) + 1 of every
  /// structure (0 up to rounding: docs/math.md 3.6).
  double max_overlap_difference = 0;
};

/// A level with new faces over (some of) `source`'s vertices, keeping `source`'s tags:
/// vertex v of `source` is vertex `index[v]` (-1: dropped), new vertices follow up to
/// `num_vertices`; faces are given as sizes + indices, and `face_source[f]` is the `source`
/// face whose hole flag face f takes (-1: not a hole). Edge sharpness is carried over for
/// edges whose two ends are kept and still joined; new edges are smooth.
/// \throw InvalidMeshError if the faces do not form a valid mesh
SubdivLevel rebuild_level(const SubdivLevel& source, const std::vector<int>& index, int num_vertices,
                          const std::vector<int>& sizes, const std::vector<int>& faces,
                          const std::vector<int>& face_source);

/// Refines `base` by `levels` (>= 0) levels, BP at the given structures (from
/// detect_polar_structures on `base`), Catmull-Clark elsewhere.
PolarRefinement refine_with_polar(const SubdivLevel& base, const std::vector<Point3>& positions, int levels,
                                  const std::vector<PolarStructure>& structures);

}  // namespace subd2nurbs
