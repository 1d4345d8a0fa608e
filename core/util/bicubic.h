// A bicubic over a 4 x 4 net (row i along u, column j along v) from its basis values in u and
// v: position and first derivatives, contracted along v first (four row sums), then along u.
#pragma once

#include "core/util/point3.h"

namespace subd2nurbs {

/// p = sum bu_i bv_j P_ij, du = sum dbu_i bv_j P_ij, dv = sum bu_i dbv_j P_ij (net[4 i + j]).
inline void bicubic_first(const Point3* net, const double bu[4], const double dbu[4], const double bv[4],
                          const double dbv[4], Point3& p, Point3& du, Point3& dv) {
  p = du = dv = Point3{0, 0, 0};
  for (int i = 0; i < 4; ++i) {
    double row[3] = {0, 0, 0}, drow[3] = {0, 0, 0};
    for (int j = 0; j < 4; ++j) {
      const Point3& P = net[4 * i + j];
      for (int c = 0; c < 3; ++c) {
        row[c] += bv[j] * P[c];
        drow[c] += dbv[j] * P[c];
      }
    }
    for (int c = 0; c < 3; ++c) {
      p[c] += bu[i] * row[c];
      du[c] += dbu[i] * row[c];
      dv[c] += bu[i] * drow[c];
    }
  }
}

}  // namespace subd2nurbs
