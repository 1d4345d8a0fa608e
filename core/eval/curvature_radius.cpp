#include "core/eval/curvature_radius.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/nurbs/nurbs_eval.h"
#include "core/util/vec3.h"

namespace subd2nurbs {

namespace {

using vec3::dot;
using vec3::cross;

/// The distinct knots of a knot vector refined n times per span.
std::vector<double> grid(const KnotVector& kv, int n) {
  std::vector<double> out;
  for (size_t i = 0; i + 1 < kv.knots.size(); ++i)
    for (int j = 0; j < n; ++j) out.push_back(kv.knots[i] + (kv.knots[i + 1] - kv.knots[i]) * j / n);
  out.push_back(kv.knots.back());
  return out;
}

/// Sign of the volume the patches enclose with their normals Xu x Xv (divergence theorem on
/// the sampling grid, trapezoid weights): > 0 when they face outward.
double signed_volume(const PatchSet& ps, int n) {
  double volume = 0;
  for (const NurbsPatch& patch : ps.patches) {
    const PatchEvaluator eval(patch);
    const std::vector<double> us = grid(patch.knots_u, n), vs = grid(patch.knots_v, n);
    for (size_t a = 0; a < us.size(); ++a)
      for (size_t b = 0; b < vs.size(); ++b) {
        const double wu = (a == 0 ? us[1] - us[0] : a + 1 == us.size() ? us[a] - us[a - 1] : us[a + 1] - us[a - 1]) / 2;
        const double wv = (b == 0 ? vs[1] - vs[0] : b + 1 == vs.size() ? vs[b] - vs[b - 1] : vs[b + 1] - vs[b - 1]) / 2;
        const SurfaceDerivs d = eval.derivs(us[a], vs[b], 1);
        volume += wu * wv * dot(d.p, cross(d.du, d.dv));
      }
  }
  return volume / 3;
}

}  // namespace

CurvatureRadii smallest_curvature_radii(const PatchSet& ps, int samples_per_span) {
  const int n = std::max(1, samples_per_span);
  CurvatureRadii r;
  double sign = 1;
  if (ps.closed && signed_volume(ps, n) < 0) sign = -1;
  r.outward = ps.closed;
  // Largest curvature each way; below 1e-9 / model size a surface counts as flat (the
  // rounding of a plane's second derivatives would otherwise give radii of 1e15).
  const double flat = 1e-9 / (ps.model_size > 0 ? ps.model_size : 1.0);
  double max_convex = flat, max_concave = flat;
  for (size_t p = 0; p < ps.patches.size(); ++p) {
    const NurbsPatch& patch = ps.patches[p];
    const PatchEvaluator eval(patch);
    for (double u : grid(patch.knots_u, n))
      for (double v : grid(patch.knots_v, n)) {
        const SurfaceDerivs d = eval.derivs(u, v, 2);
        Point3 normal = unit_normal(d);
        if (dot(normal, normal) == 0) continue;  // singular (a polar cap's pole)
        for (double& c : normal) c *= sign;
        // First and second fundamental forms; H and K; k = H +- sqrt(H^2 - K), signed so
        // that a surface curving away from the normal (a sphere, outward) has k < 0.
        const double E = dot(d.du, d.du), F = dot(d.du, d.dv), G = dot(d.dv, d.dv);
        const double L = dot(d.duu, normal), M = dot(d.duv, normal), N = dot(d.dvv, normal);
        const double det = E * G - F * F;
        if (!(det > 0)) continue;
        const double H = (E * N - 2 * F * M + G * L) / (2 * det), K = (L * N - M * M) / det;
        const double root = std::sqrt(std::max(0.0, H * H - K));
        const double k_max = H + root, k_min = H - root;
        ++r.samples;
        auto at = [&](CurvatureRadiusAt& w, double k) {
          w.radius = 1 / k;
          w.patch = static_cast<int>(p);
          w.u = u;
          w.v = v;
          w.point = d.p;
        };
        if (-k_min > max_convex) { max_convex = -k_min; at(r.inward, -k_min); }
        if (k_max > max_concave) { max_concave = k_max; at(r.outward_offset, k_max); }
      }
  }
  return r;
}

}  // namespace subd2nurbs
