// A bicubic over a 4 x 4 net (row i along u, column j along v) from its basis values in u and
// v: position and first derivatives, contracted along v first (four row sums), then along u;
// and the uniform cubic B-spline basis on one span.
#pragma once

#include "core/util/point3.h"

namespace subd2nurbs {

/// Uniform cubic B-spline basis on one span, x in [0, 1]: values N, first and second derivatives.
inline void bspline_basis(double x, double N[4], double D[4], double DD[4]) {
  const double x2 = x * x, x3 = x2 * x, y = 1 - x;
  N[0] = y * y * y / 6;
  N[1] = (3 * x3 - 6 * x2 + 4) / 6;
  N[2] = (-3 * x3 + 3 * x2 + 3 * x + 1) / 6;
  N[3] = x3 / 6;
  D[0] = -y * y / 2;
  D[1] = (9 * x2 - 12 * x) / 6;
  D[2] = (-9 * x2 + 6 * x + 3) / 6;
  D[3] = x2 / 2;
  DD[0] = y;
  DD[1] = 3 * x - 2;
  DD[2] = -3 * x + 1;
  DD[3] = x;
}

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
