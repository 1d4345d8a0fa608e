// A small hand-made PatchSet exercising every field of the JSON export (header-only; used by
// test_patch_json.cpp and by the sample writer behind the Python check).
#pragma once

#include <cmath>
#include <limits>

#include "core/nurbs/patch_set.h"

namespace subd2nurbs::testing {

/// Three patches (a Bezier patch on a plane, a rational patch with an interior u knot, a polar
/// cap with awkward numbers), two boundary curves and three corners. Patches 0 and 1 lie on
/// the plane z = 0.1 + 2x - 0.7y; patch 0 (poles at the Greville abscissae, no weights) is
/// parametrised by x = u, y = v.
inline PatchSet sample_patch_set() {
  PatchSet ps;
  ps.model_size = 2.0 / 3.0;
  ps.closed = false;
  auto plane = [](double x, double y) -> Point3 { return {x, y, 0.1 + 2 * x - 0.7 * y}; };

  NurbsPatch bez;
  bez.kind = PatchKind::RegularBSpline;
  bez.knots_u = {{0.0, 1.0}, {4, 4}, false};
  bez.knots_v = bez.knots_u;
  bez.num_poles_u = bez.num_poles_v = 4;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) bez.poles.push_back(plane(i / 3.0, j / 3.0));
  bez.base_faces = {7};
  bez.corners = {{0, 1, 2, -1}};
  bez.curves = {{0, -1, 1, -1}};
  bez.curve_reversed = {{false, false, true, false}};
  ps.patches.push_back(bez);

  NurbsPatch rat;
  rat.kind = PatchKind::Pccm;
  rat.knots_u = {{0.0, 0.5, 1.0}, {4, 1, 4}, false};
  rat.knots_v = {{0.0, 1.0}, {4, 4}, false};
  rat.num_poles_u = 5;
  rat.num_poles_v = 4;
  const double greville_u[5] = {0.0, 1.0 / 6, 0.5, 5.0 / 6, 1.0};
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 4; ++j) {
      rat.poles.push_back(plane(greville_u[i], j / 3.0));
      rat.weights.push_back(1.0 + 0.1 * ((3 * i + j) % 5));
    }
  rat.base_faces = {3, 4, 5};
  rat.curves = {{1, -1, -1, -1}};
  rat.curve_reversed = {{true, false, false, false}};
  ps.patches.push_back(rat);

  NurbsPatch cap;
  cap.kind = PatchKind::PolarCap;
  cap.degree_u = 3;
  cap.degree_v = 2;
  cap.knots_u = {{0.0, 1.0}, {4, 4}, false};
  cap.knots_v = {{0.0, 1.0}, {3, 3}, false};
  cap.num_poles_u = 4;
  cap.num_poles_v = 3;
  const double odd[] = {-0.0, 5e-324, 1e-300, 1.2345678901234567e+300, -2.5, 0.1, 1.0 / 3,
                        -7.0 / 9, 123456789.125, 3.141592653589793, 2.2250738585072014e-308, 1e22};
  for (int k = 0; k < 12; ++k) cap.poles.push_back({odd[k], -odd[(k + 5) % 12], odd[(k + 7) % 12]});
  cap.base_faces = {};
  ps.patches.push_back(cap);

  BoundaryCurve c0;
  c0.corner0 = 0;
  c0.corner1 = 1;
  c0.knots = {{0.0, 1.0}, {4, 4}, false};
  c0.poles = {plane(0, 0), plane(1.0 / 3, 0), plane(2.0 / 3, 0), plane(1, 0)};
  c0.uses = {{0, 0, false}};
  c0.continuity = Continuity::Boundary;
  ps.curves.push_back(c0);

  BoundaryCurve c1;
  c1.corner0 = 2;
  c1.corner1 = 2;
  c1.knots = {{0.0, 0.25, 1.0}, {4, 2, 4}, false};
  c1.poles = {{1, 1, 1}, {0.5, 1, 1}, {0.25, 1, 1}, {0.1, 1, 1}, {0.05, 1, 1}, {0, 1, 1}};
  c1.uses = {{0, 2, true}, {1, 0, true}};
  c1.continuity = Continuity::G1;
  ps.curves.push_back(c1);

  ps.corners = {{plane(0, 0), 0}, {plane(1, 0), 12}, {{0.1, -0.2, 1.0 / 7}, -1}};
  return ps;
}

}  // namespace subd2nurbs::testing
