// Helpers shared by the patch tests: building from a MeshInput, evaluating the level-k Bezier
// pieces, and the exact checks of MATH.md section 9.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/eval/nurbs_eval.h"
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

/// Patch-frame coordinates (s, t) of a level-k quad whose frame corner has rotation r in its
/// face -> the face's own coordinates.
inline void frame_to_face(int r, double s, double t, double& fu, double& fv) {
  switch (r) {
    case 0: fu = s; fv = t; break;
    case 1: fu = 1 - t; fv = s; break;
    case 2: fu = 1 - s; fv = 1 - t; break;
    default: fu = t; fv = 1 - s; break;
  }
}

/// Calls fn(patch, x, y, N, corner) for each level-k quad of each patch: the N x N grid of
/// PatchBuildInfo::sub_corners, x along u, `corner` the quad's level-k frame corner. Polar
/// caps have no grid and are skipped.
template <class Fn>
void for_each_sub_quad(const PatchBuild& b, Fn&& fn) {
  const int N = 1 << (b.info.level - b.info.coarse_level);
  for (size_t pi = 0; pi < b.set.patches.size(); ++pi) {
    const auto& grid = b.info.sub_corners[pi];
    if (grid.empty()) continue;
    for (int y = 0; y < N; ++y)
      for (int x = 0; x < N; ++x) fn(static_cast<int>(pi), x, y, N, grid[y * N + x]);
  }
}

/// Max distance between each merged patch and its level-k Bezier pieces (5x5 samples each).
inline double max_piece_error(const PatchBuild& b) {
  const PolyMesh& mk = b.refinement.levels[b.info.level].mesh;
  double worst = 0;
  for_each_sub_quad(b, [&](int pi, int x, int y, int N, int c) {
    const int f = mk.corner_face(c), r = c - mk.face_begin(f);
    for (int a = 0; a <= 4; ++a)
      for (int bb = 0; bb <= 4; ++bb) {
        const double s = a / 4.0, t = bb / 4.0;
        double fu, fv;
        frame_to_face(r, s, t, fu, fv);
        const Eigen::Vector3d q = eval_bezier(&b.level_nets[static_cast<size_t>(f) * 16], fu, fv);
        const SurfaceDerivs d = evaluate(b.set.patches[pi], (x + s) / N, (y + t) / N);
        worst = std::max(worst, (ev(d.p) - q).norm());
      }
  });
  return worst;
}

/// Max distance between the patches at the corners of their level-k quads and the limit
/// positions of the level-k vertices there, over vertices whose quads are all regular
/// (where the patch is the exact limit surface).
inline double max_corner_limit_error(const PatchBuild& b) {
  const SubdivLevel& lk = b.refinement.levels[b.info.level];
  const PolyMesh& mk = lk.mesh;
  std::vector<Point3> limit;
  limit_stencils(lk).apply(b.level_positions, limit);
  std::vector<char> near_fan(mk.num_vertices(), 0);
  for (const IrregularFan& f : b.info.fans) {
    const int* cs = mk.vertex_corners(f.vertex);
    for (int i = 0; i < mk.vertex_face_count(f.vertex); ++i) {
      const int face = mk.corner_face(cs[i]);
      for (int h = mk.face_begin(face); h < mk.face_end(face); ++h) near_fan[mk.corner_vertex(h)] = 1;
    }
  }
  double worst = 0;
  for_each_sub_quad(b, [&](int pi, int x, int y, int N, int c) {
    const int v = mk.corner_vertex(c);
    if (near_fan[v]) return;
    const SurfaceDerivs d = evaluate(b.set.patches[pi], static_cast<double>(x) / N, static_cast<double>(y) / N);
    worst = std::max(worst, (ev(d.p) - ev(limit[v])).norm());
  });
  return worst;
}

/// Max over the G1 rays of |D + E - 2c(1-t)^2 e'| / |e'| on the first level-k segment
/// (MATH.md 5.3 and 9), D and E the cross derivatives into the two patches, e' the derivative
/// along the ray away from the extraordinary vertex. All three are taken in patch parameters,
/// which scales them equally.
inline double max_g1_residual(const PatchBuild& b, int samples = 17) {
  double worst = 0;
  const int N = 1 << (b.info.level - b.info.coarse_level);
  for (const RayCurve& ray : b.info.rays) {
    if (ray.continuity != Continuity::G1) continue;
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
