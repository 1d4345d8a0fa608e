// Point3 (plain array, the PatchSet's type) <-> Eigen vectors for the geometry code.
#pragma once

#include <Eigen/Core>

#include "core/util/point3.h"

namespace subd2nurbs {

inline Eigen::Vector3d to_eigen(const Point3& p) { return {p[0], p[1], p[2]}; }
inline Point3 to_point(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace subd2nurbs
