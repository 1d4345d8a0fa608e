// Tolerances of the geometry core, in one place. Each is relative to the model size (the
// bounding-box diagonal of the cage) unless its comment says otherwise.
#pragma once

namespace subd2nurbs::tolerances {

/// A simple knot is removed when removing it moves the surface by at most this (relative):
/// the third-derivative jump across the knot line, as a position (knot_assembly.h). Rounding
/// in 20 levels of refinement stays near 1e-14; real features at any depth are far above.
constexpr double kKnotRemoval = 1e-12;

/// Two evaluations this close (relative) are the same surface point up to rounding: the quality
/// report does not search for a closer limit point below it.
constexpr double kSameSurface = 1e-12;

}  // namespace subd2nurbs::tolerances
