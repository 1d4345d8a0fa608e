// Tolerances of the geometry core, in one place. Each is relative to the model size (the
// bounding-box diagonal of the cage) unless its comment says otherwise.
#pragma once

namespace subd2nurbs::tolerances {

/// A simple knot is a candidate for removal when the third-derivative jump across its line, as a
/// position at the pieces' scale (knot_assembly.h), is at most this (relative): rounding noise
/// measured 1e-15 .. 6e-15 on the corpus (catmark_rook at level 8); real jumps decay towards an
/// extraordinary vertex and were seen down to 4e-13. The patch is then checked against every
/// piece (kSameSurface) and a knot is put back where it is needed.
constexpr double kKnotRemoval = 5e-14;

/// Two evaluations this close (relative) are the same surface point up to rounding: a patch
/// reproduces its pieces when it is this close to each, and the quality report does not search
/// for a closer limit point below it.
constexpr double kSameSurface = 1e-12;

}  // namespace subd2nurbs::tolerances
