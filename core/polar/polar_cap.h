// The finite singular polar cap (docs/math.md section 4; Myles-Karciauskas-Peters 2008, section 3):
// one polynomial bicubic B-spline per polar structure, periodic around the pole, with its
// u = 0 edge collapsed to the BP limit point, and joining the surrounding bicubic surface C2
// along the polar structure's 2-link (ring 2 of the input).
//
// Steps (docs/math.md 4.1): (i) `radial_steps` radial BP steps of rings 0..3; (ii) row r = ring r,
// column j = spoke j, column j centred at v = j; (iii) row 0 := the BP limit point, u knots
// start with a 4-fold knot; (iv) row 1 := its projection onto the first Fourier mode scaled by
// lambda, so that the limit normal is defined and equals BP's; (v) clamp the outer end.
#pragma once

#include <vector>

#include "core/nurbs/patch_set.h"
#include "core/polar/polar_net.h"
#include "core/polar/polar_structure.h"

namespace subd2nurbs {

struct PolarCapOptions {
  int radial_steps = 1;   ///< radial BP pre-steps (1 or 2 in the front ends; >= 1 required)
  double lambda = 0.75;   ///< scale of the projected 1-link (docs/math.md 4.1 (iv)); > 0
};

struct PolarCap {
  int n = 0;                ///< spokes (pole valence)
  int m = 0;                ///< u domain [0, m]: 3 after one radial step, 7 after two
  int radial_steps = 1;     ///< as built (m = 2^(radial_steps + 1) - 1)
  Point3 centre{};          ///< row 0: the BP limit point of the pole
  Point3 normal{};          ///< BP limit normal at the pole (unit)
  /// The periodic net before clamping: rows c_0..c_{m+2} (radial), n columns each; row 0 is
  /// the centre repeated. u knots 0,0,0,0,1,2,...,m+3; column j is centred at v = j.
  std::vector<Point3> rows;
  const Point3& c(int r, int j) const { return rows[static_cast<size_t>(r) * n + j]; }
};

/// Rings 0..3 of a detected structure as a polar net.
PolarNet polar_net_of(const PolarStructure& s, const std::vector<Point3>& positions);

/// Steps (i)-(iv). \throw std::invalid_argument for fewer than 4 rings, n < 3,
/// radial_steps < 1 or lambda <= 0
PolarCap build_polar_cap(const PolarNet& rings0to3, const PolarCapOptions& options = {});

/// The cap as a clamped PatchSet patch over [0,1]^2 (step (v) and the seam clamp of docs/math.md
/// 4.4): u radial (u = 0 the collapsed pole, u = 1 the 2-link), v around the pole with spoke
/// j at v = j / n. `circular_refinements` circular knot-insertion steps first (exact), so
/// that the boundary has n * 2^circular_refinements spans, one per neighbouring patch.
NurbsPatch polar_cap_patch(const PolarCap& cap, int circular_refinements = 0);

/// The cap next to its pole, over 64 directions: the angle between its normal and the BP
/// limit normal, and the largest principal curvature |k|, at radial distances 1e-2 and 1e-4
/// (in cap spans) from the collapsed edge. Evaluated relative to the centre. Bounded
/// curvature means the two maxima are close (docs/math.md 4.3, 10.5).
struct CapPoleMeasure {
  double distance[2] = {1e-2, 1e-4};
  double normal_angle_deg[2] = {0, 0};
  double max_abs_k[2] = {0, 0};
};
CapPoleMeasure measure_cap_pole(const PolarCap& cap, const NurbsPatch& patch);

/// Largest distance from the BP limit surface of rings 0..3 to the cap `patch` (built from
/// them): the pole's limit point, and the limit points of the grid after `levels` radial BP
/// steps from ring 3 (where BP is the tensor spline, so bp_grid_limit is exact) out to the
/// cap's boundary, each projected onto the patch (damped Gauss-Newton). The cap equals the
/// BP limit beyond input ring 3 / 2^radial_steps, so this measures the pole region only.
double cap_distance_to_bp(const PolarNet& rings0to3, const PolarCap& cap, const NurbsPatch& patch, int levels = 6);

}  // namespace subd2nurbs
