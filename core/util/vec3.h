// Small vector arithmetic on Point3 (core/util/point3.h) for the files that want it without
// Eigen: include this header instead of defining the helpers again in an anonymous namespace.
#pragma once

#include <cmath>

#include "core/util/point3.h"

namespace subd2nurbs::vec3 {

inline Point3 sub(const Point3& a, const Point3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline double dot(const Point3& a, const Point3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Point3 cross(const Point3& a, const Point3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline double norm(const Point3& a) { return std::sqrt(dot(a, a)); }
/// a + s d
inline Point3 axpy(const Point3& a, double s, const Point3& d) { return {a[0] + s * d[0], a[1] + s * d[1], a[2] + s * d[2]}; }
inline double dist2(const Point3& a, const Point3& b) {
  const Point3 d = sub(a, b);
  return dot(d, d);
}

}  // namespace subd2nurbs::vec3
