// Bi-cubic polar (BP) subdivision on a polar net (docs/math.md section 3; Karciauskas & Peters 2007,
// with the parameters of Myles-Karciauskas-Peters 2008: beta = 5/8, alpha = 3/8).
//
// A polar net is a pole p0 and R rings of n points each. Ring r (r >= 1), spoke j is
// at(r, j); spoke j+1 follows spoke j counter-clockwise about the outward normal, so the
// fan triangle at the pole is (p0, at(1, j), at(1, j+1)). at(0, j) is the pole for every j.
#pragma once

#include <vector>

#include "core/util/point3.h"

namespace subd2nurbs {

struct PolarNet {
  int n = 0;                  ///< points per ring (the valence of the pole)
  Point3 pole{};
  std::vector<Point3> rings;  ///< ring r (1-based), spoke j at (r - 1) * n + j

  int num_rings() const { return n > 0 ? static_cast<int>(rings.size()) / n : 0; }
  /// Point of ring r, spoke j (j taken modulo n; r = 0 is the pole).
  const Point3& at(int r, int j) const;
  Point3& at(int r, int j);
};

/// BP weights. beta = 5/8 gives the C1, bounded-curvature spectrum for n >= 6 (docs/math.md 3.4).
struct BpParameters {
  double beta = 5.0 / 8.0;
  double alpha() const { return beta - 0.25; }
};

/// One radial BP step (docs/math.md 3.2): rings 0..R become rings 0..2R-1; n is unchanged.
/// \throw std::invalid_argument for fewer than 2 rings or n < 3
PolarNet radial_step(const PolarNet& net, const BpParameters& bp = {});

/// One circular step (docs/math.md 3.3): every ring is refined as a closed uniform cubic B-spline
/// (knot insertion), n becomes 2n; the pole is unchanged. The result is not a BP net: BP
/// continues from the radial-only net (docs/math.md 3.6).
PolarNet circular_step(const PolarNet& net);

/// Limit point of the pole under BP subdivision (docs/math.md 3.5): ((1-beta) p0 + alpha m) /
/// (1 - beta + alpha), m the mean of ring 1; (p0 + m) / 2 for beta = 5/8.
Point3 bp_limit_point(const PolarNet& net, const BpParameters& bp = {});

/// Unit limit normal at the pole (docs/math.md 3.5): t1 x t2 with t1 = sum cos(theta_j) ring1_j,
/// t2 = sum sin(theta_j) ring1_j. Valid for a radial-only net with n >= 5.
Point3 bp_limit_normal(const PolarNet& net);

/// Limit point of ring r >= 3, spoke j of a radial-only BP net with at least r + 1 rings:
/// there BP is the uniform bicubic B-spline of the (ring, spoke) grid, so this is the tensor
/// product vertex mask (1, 4, 1)/6 x (1, 4, 1)/6.
Point3 bp_grid_limit(const PolarNet& net, int r, int j);

}  // namespace subd2nurbs
