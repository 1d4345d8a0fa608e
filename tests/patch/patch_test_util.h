// Helpers shared by the patch tests: building from a MeshInput, evaluating the level-k Bezier
// pieces, and the exact checks of MATH.md section 9.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/nurbs/nurbs_eval.h"
#include "core/eval/quality.h"
#include "core/limit/limit_evaluator.h"
#include "core/patch/patch_builder.h"

namespace subd2nurbs::testing {

inline PatchBuild build_from_input(const MeshInput& in, int extra_levels = 0) {
  const SubdivLevel base = SubdivLevel::from_input(in);
  PatchOptions o;
  o.extra_levels = extra_levels;
  return build_patches(base, in.positions, o);
}

inline Eigen::Vector3d ev(const Point3& p) { return {p[0], p[1], p[2]}; }

/// A cubic Bezier net (16 points, index i * 4 + j) at (s, t).
inline Eigen::Vector3d eval_bezier(const Point3* net, double s, double t) {
  auto B = [](int i, double x) {
    const double y = 1 - x;
    return i == 0 ? y * y * y : i == 1 ? 3 * x * y * y : i == 2 ? 3 * x * x * y : x * x * x;
  };
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) p += B(i, s) * B(j, t) * ev(net[i * 4 + j]);
  return p;
}

/// Calls fn(patch, leaf) for every polynomial piece of every patch (polar caps have none).
template <class Fn>
void for_each_leaf(const PatchBuild& b, Fn&& fn) {
  for (size_t pi = 0; pi < b.leaves.size(); ++pi)
    for (const PatchLeaf& leaf : b.leaves[pi]) fn(static_cast<int>(pi), leaf);
}

/// Max distance between each patch and its pieces (5x5 samples each): the knot assembly
/// must reproduce every piece exactly.
inline double max_piece_error(const PatchBuild& b) {
  double worst = 0;
  for_each_leaf(b, [&](int pi, const PatchLeaf& leaf) {
    for (int a = 0; a <= 4; ++a)
      for (int bb = 0; bb <= 4; ++bb) {
        const double s = a / 4.0, t = bb / 4.0;
        const Eigen::Vector3d q = eval_bezier(leaf.net.data(), s, t);
        const SurfaceDerivs d = evaluate(b.set.patches[pi], leaf.u0 + s * leaf.size, leaf.v0 + t * leaf.size);
        worst = std::max(worst, (ev(d.p) - q).norm());
      }
  });
  return worst;
}

/// Max distance between the patches and the exact limit surface (core/limit) at the corners
/// and centres of their regular pieces (not Construction Q zones), where the patch is the limit.
inline double max_corner_limit_error(const PatchBuild& b) {
  const LimitEvaluator limit(b.refinement.levels[0], b.cage_positions);
  double worst = 0;
  for_each_leaf(b, [&](int pi, const PatchLeaf& leaf) {
    if (leaf.zone) return;
    for (double s : {0.0, 0.5, 1.0})
      for (double t : {0.0, 0.5, 1.0}) {
        const double u = leaf.u0 + s * leaf.size, v = leaf.v0 + t * leaf.size;
        const LimitParam lp = patch_to_limit(b, pi, u, v);
        const LimitPoint q = limit.evaluate_point(lp.face, lp.sub, lp.u, lp.v);
        const SurfaceDerivs d = evaluate(b.set.patches[pi], u, v);
        worst = std::max(worst, (ev(d.p) - ev(q.p)).norm());
      }
  });
  return worst;
}

/// For every simple interior knot of every patch (both directions): the largest third-derivative
/// jump across its line, computed from the patch alone (third differences at 4 points of each
/// adjacent span, exact for a cubic, with coordinates relative to the patch's first pole), as a
/// position at the patch's own scale: |jump| h^3 / 6, h the smaller adjacent span. Calls
/// fn(patch, across_u, knot, position_jump, coarse_jump) with coarse_jump in patch parameters.
template <class Fn>
void for_each_simple_knot_jump(const PatchBuild& b, Fn&& fn) {
  for (size_t pi = 0; pi < b.set.patches.size(); ++pi) {
    const NurbsPatch& p = b.set.patches[pi];
    if (p.kind == PatchKind::PolarCap) continue;
    const Eigen::Vector3d o = ev(p.poles[0]);
    for (int dir = 0; dir < 2; ++dir) {
      const KnotVector& kv = dir == 0 ? p.knots_u : p.knots_v;
      const KnotVector& other = dir == 0 ? p.knots_v : p.knots_u;
      for (size_t k = 1; k + 1 < kv.knots.size(); ++k) {
        if (kv.mults[k] != 1) continue;
        const double a = kv.knots[k - 1], xi = kv.knots[k], c = kv.knots[k + 1];
        double worst_pos = 0, worst_coarse = 0;
        for (size_t m = 0; m + 1 < other.knots.size(); ++m)
          for (double f : {0.2, 0.5, 0.8}) {
            const double t = other.knots[m] + f * (other.knots[m + 1] - other.knots[m]);
            auto at = [&](double x) {
              const SurfaceDerivs d = dir == 0 ? evaluate(p, x, t) : evaluate(p, t, x);
              return Eigen::Vector3d(ev(d.p) - o);
            };
            auto third = [&](double lo, double hi) {
              const double step = (hi - lo) / 3;
              const Eigen::Vector3d d3 = at(hi) - 3 * at(lo + 2 * step) + 3 * at(lo + step) - at(lo);
              return Eigen::Vector3d(d3 / (step * step * step));
            };
            const double jump = (third(xi, c) - third(a, xi)).norm();
            const double h = std::min(xi - a, c - xi);
            worst_pos = std::max(worst_pos, jump * h * h * h / 6);
            worst_coarse = std::max(worst_coarse, jump);
          }
        fn(static_cast<int>(pi), dir == 0, xi, worst_pos, worst_coarse);
      }
    }
  }
}

/// Max over the G1 rays of |D + E - 2c(1-t)^2 e'| / |e'| on the first level-k segment
/// (MATH.md 5.3 and 9), D and E the cross derivatives into the two patches, e' the derivative
/// along the ray away from the extraordinary vertex. All three are taken in patch parameters,
/// which scales them equally.
inline double max_g1_residual(const PatchBuild& b, int samples = 17) {
  double worst = 0;
  for (const RayCurve& ray : b.info.rays) {
    if (ray.continuity != Continuity::G1) continue;
    const int N = 1 << (b.info.fans[ray.fan].level - b.info.coarse_level);
    const double c = ray.c;
    const BoundaryCurve& bc = b.set.curves[ray.curve];
    for (int k = 0; k < samples; ++k) {
      const double t = static_cast<double>(k) / (samples - 1);  // along the first segment
      const double s = ray.vertex_at_start ? t / N : 1 - t / N;
      Eigen::Vector3d inward[2], along;
      for (int w = 0; w < 2; ++w) {
        const CurveUse& u = bc.uses[w];
        const double side_t = u.side_parameter(s);
        const SideDerivs d = side_derivatives(b.set.patches[u.patch], u.side, side_t);
        const Eigen::Vector3d a = ev(d.along), in = ev(d.inward);
        inward[w] = in;
        if (w == 0) {
          // a is d/d(side_t); convert to d/ds, then to "away from the vertex".
          Eigen::Vector3d dds = u.reversed ? Eigen::Vector3d(-a) : a;
          along = ray.vertex_at_start ? dds : Eigen::Vector3d(-dds);
        }
      }
      const double alpha = 2 * c * (1 - t) * (1 - t);
      const double res = (inward[0] + inward[1] - alpha * along).norm() / along.norm();
      worst = std::max(worst, res);
    }
  }
  return worst;
}

}  // namespace subd2nurbs::testing
