// The smallest radius of curvature of the patches (issue 33): how thick a shell or offset the
// body can take before the offset surface folds over itself. Sampled densely on every knot
// span of every patch (principal curvatures of the B-spline surfaces themselves, not the
// limit), split by side: an inward offset (a shell, hollowing) of thickness t folds where the
// surface curves away from its outward normal with radius below t (convex parts), an outward
// offset where it curves towards it (concave parts). docs/downstream.md.
#pragma once

#include <limits>

#include "core/nurbs/patch_set.h"

namespace subd2nurbs {

/// Where a radius was found: the patch (face) and its parameters in the patch's own domain.
struct CurvatureRadiusAt {
  double radius = std::numeric_limits<double>::infinity();  ///< infinity: no such curvature
  int patch = -1;
  double u = 0, v = 0;
  Point3 point{};
};

struct CurvatureRadii {
  int samples = 0;  ///< samples with a regular parametrization (a polar cap's pole is skipped)
  /// Normals taken outward (a closed PatchSet whose patches face inward is measured turned
  /// around); for an open PatchSet, the side the patches' normals Xu x Xv point to.
  bool outward = false;
  /// The smallest radius where the surface curves away from the normal (convex: a sphere
  /// everywhere): the largest inward offset / shell thickness before the offset folds.
  /// Curvatures below 1e-9 / model size count as flat (radius infinity, patch -1).
  CurvatureRadiusAt inward;
  /// The smallest radius where it curves towards the normal (concave): the largest outward
  /// offset before it folds.
  CurvatureRadiusAt outward_offset;
};

/// Principal curvatures of every patch on a (n + 1) x (n + 1) grid per knot span (span ends
/// included), n = samples_per_span >= 1. Pure; cost O(patches x spans x n^2).
CurvatureRadii smallest_curvature_radii(const PatchSet& ps, int samples_per_span = 8);

}  // namespace subd2nurbs
