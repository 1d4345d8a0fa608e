// Point3: a point or vector as three doubles, the plain type of positions in the core's
// interfaces (PatchSet, stencil tables). Eigen conversions: core/util/eigen_point.h.
#pragma once

#include <array>

namespace subd2nurbs {

using Point3 = std::array<double, 3>;

}  // namespace subd2nurbs
