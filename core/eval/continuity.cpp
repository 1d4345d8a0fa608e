#include "core/eval/continuity.h"

#include "core/util/parallel.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/nurbs/nurbs_eval.h"
#include "core/util/constants.h"
#include "core/util/eigen_point.h"

namespace subd2nurbs {
namespace {

using V3 = Eigen::Vector3d;

// The side frame of nurbs_eval.h in Eigen vectors.
struct SideFrame {
  V3 p, along, inward, inward2, normal;
};
SideFrame side_frame(const PatchEvaluator& patch, int side, double t) {
  const SideDerivs d = side_derivatives(patch, side, t);
  return {to_eigen(d.p), to_eigen(d.along), to_eigen(d.inward), to_eigen(d.inward2), to_eigen(d.normal)};
}

double angle_deg(const V3& a, const V3& b) {
  if (a.norm() == 0 || b.norm() == 0) return 0;
  // atan2 of |a x b| and a.b keeps precision for tiny angles (acos floors at ~1e-6 degrees).
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / kPi;
}

}  // namespace

CurveMeasure measure_curve(const PatchSet& ps, int ci, int samples) {
  const BoundaryCurve& c = ps.curves[ci];
  CurveMeasure m;
  m.curve = ci;
  m.claimed = c.continuity;
  if (c.uses.size() < 2) return m;
  const CurveUse& A = c.uses[0];
  const CurveUse& B = c.uses[1];
  // A curve of several spans (e.g. coarse edges joined along a packed face) gets `samples`
  // per span.
  const int n = 1 + (samples - 1) * std::max<int>(1, static_cast<int>(c.knots.knots.size()) - 1);
  const PatchEvaluator pa(ps.patches[A.patch]), pb(ps.patches[B.patch]);
  for (int k = 0; k < n; ++k) {
    const double s = static_cast<double>(k) / (n - 1);
    const SideFrame fa = side_frame(pa, A.side, A.side_parameter(s));
    const SideFrame fb = side_frame(pb, B.side, B.side_parameter(s));
    m.gap = std::max(m.gap, (fa.p - fb.p).norm());
    // A singular point (a polar cap's pole, at the end of its seam) has no normal and no
    // cross derivatives to compare.
    if (fa.normal.norm() == 0 || fb.normal.norm() == 0) continue;
    const double ang = angle_deg(fa.normal, fb.normal);
    if (ang > m.normal_angle_deg) { m.normal_angle_deg = ang; m.worst_s = s; }
    const V3& D = fa.inward;
    const V3& E = fb.inward;
    const V3 e = A.reversed ? V3(-fa.along) : fa.along;
    const double den = D.norm() * E.norm() * e.norm();
    if (den > 0) m.coplanarity = std::max(m.coplanarity, std::abs(D.cross(E).dot(e)) / den);
    const double scale1 = std::max(D.norm(), E.norm());
    if (scale1 > 0) m.c1_jump = std::max(m.c1_jump, (D + E).norm() / scale1);
    const double scale2 = std::max({fa.inward2.norm(), fb.inward2.norm(), scale1});
    if (scale2 > 0) m.c2_jump = std::max(m.c2_jump, (fa.inward2 - fb.inward2).norm() / scale2);
  }
  return m;
}

ContinuityReport measure_continuity(const PatchSet& ps, int samples) {
  ContinuityReport r;
  // Curves are measured in parallel and summarised in curve order.
  const int n = static_cast<int>(ps.curves.size());
  std::vector<CurveMeasure> measured(n);
  parallel_for(n, [&](int ci) {
    if (ps.curves[ci].uses.size() >= 2) measured[ci] = measure_curve(ps, ci, samples);
  });
  for (int ci = 0; ci < n; ++ci) {
    if (ps.curves[ci].uses.size() < 2) continue;
    const CurveMeasure& m = measured[ci];
    r.max_gap = std::max(r.max_gap, m.gap);
    const Continuity c = m.claimed;
    if (c == Continuity::G1 || c == Continuity::C1 || c == Continuity::C2) {
      r.max_normal_angle_deg = std::max(r.max_normal_angle_deg, m.normal_angle_deg);
      r.max_coplanarity = std::max(r.max_coplanarity, m.coplanarity);
    } else {
      r.max_crease_normal_angle_deg = std::max(r.max_crease_normal_angle_deg, m.normal_angle_deg);
    }
    if (c == Continuity::C1 || c == Continuity::C2) r.max_c1_jump = std::max(r.max_c1_jump, m.c1_jump);
    if (c == Continuity::C2) r.max_c2_jump = std::max(r.max_c2_jump, m.c2_jump);
    r.curves.push_back(m);
  }
  return r;
}

}  // namespace subd2nurbs
