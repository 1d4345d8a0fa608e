#include "core/eval/target_distance.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/util/gauss_newton.h"
#include "core/util/parallel.h"

namespace subd2nurbs {
namespace {

using Vec3 = Eigen::Vector3d;
Vec3 vec(const Point3& p) { return {p[0], p[1], p[2]}; }

struct PtexPoint {
  int ptex = -1;
  double u = 0, v = 0;
};

/// The ptex faces with a surface.
std::vector<int> surface_ptex(const LimitEvaluator& limit) {
  std::vector<int> out;
  for (int p = 0; p < limit.num_ptex_faces(); ++p)
    if (!limit.base().face_hole[limit.ptex_to_face(p)]) out.push_back(p);
  return out;
}

/// Evaluates a grid of (u, v) on every ptex face of `faces`.
void sample_grid(const LimitEvaluator& limit, const std::vector<int>& faces, const std::vector<double>& t,
                 std::vector<Point3>& pos, std::vector<PtexPoint>& where) {
  const int g = static_cast<int>(t.size()), nf = static_cast<int>(faces.size());
  pos.resize(static_cast<size_t>(nf) * g * g);
  where.resize(pos.size());
  parallel_for(nf, [&](int i) {
    const int ptex = faces[i], f = limit.ptex_to_face(ptex), sub = ptex - limit.first_ptex(f);
    std::vector<LimitSample> s(g * g);
    limit.evaluate_grid(f, sub, t.data(), g, t.data(), g, s.data());
    for (int a = 0; a < g; ++a)
      for (int b = 0; b < g; ++b) {
        const size_t k = static_cast<size_t>(i) * g * g + a * g + b;
        pos[k] = s[a * g + b].p;
        where[k] = {ptex, t[a], t[b]};
      }
  });
}

DistanceStats summarise(const std::vector<double>& d, double diagonal, int& worst) {
  DistanceStats s;
  s.count = static_cast<int>(d.size());
  if (d.empty()) return s;
  double sum2 = 0;
  worst = 0;
  for (int i = 0; i < s.count; ++i) {
    sum2 += d[i] * d[i];
    if (d[i] > d[worst]) worst = i;
  }
  std::vector<double> sorted = d;
  const size_t k = std::min(sorted.size() - 1, static_cast<size_t>(std::ceil(0.95 * sorted.size())) - 1);
  std::nth_element(sorted.begin(), sorted.begin() + k, sorted.end());
  s.max = d[worst] / diagonal;
  s.rms = std::sqrt(sum2 / s.count) / diagonal;
  s.p95 = sorted[k] / diagonal;
  return s;
}

/// Closest limit point to q on ptex face `start.ptex` by Gauss-Newton from start.
double project(const LimitEvaluator& limit, const Point3& q, PtexPoint& at) {
  const int f = limit.ptex_to_face(at.ptex), sub = at.ptex - limit.first_ptex(f);
  LimitPoint s = limit.evaluate_point(f, sub, at.u, at.v);
  double best = (vec(s.p) - vec(q)).norm();
  for (int iter = 0; iter < 12; ++iter) {
    const auto next = closest_point_step(vec(s.p) - vec(q), vec(s.du), vec(s.dv), at.u, at.v);
    if (!next) break;
    const auto [u, v] = *next;
    const LimitPoint t = limit.evaluate_point(f, sub, u, v);
    const double d = (vec(t.p) - vec(q)).norm();
    if (d >= best) break;
    const double moved = std::abs(u - at.u) + std::abs(v - at.v);
    best = d;
    at.u = u;
    at.v = v;
    s = t;
    if (moved < 1e-14) break;
  }
  return best;
}

}  // namespace

DistanceStats points_to_limit(const LimitEvaluator& limit, const std::vector<Point3>& points, double diagonal, int grid) {
  const std::vector<int> faces = surface_ptex(limit);
  std::vector<double> t(grid + 1);
  for (int i = 0; i <= grid; ++i) t[i] = static_cast<double>(i) / grid;
  std::vector<Point3> pos;
  std::vector<PtexPoint> where;
  sample_grid(limit, faces, t, pos, where);
  const ClosestPointTree tree(pos, {});
  const int np = static_cast<int>(points.size());
  std::vector<double> d(np);
  std::vector<PtexPoint> foot(np);
  // The foot may lie in a ptex face next to the nearest sample's (across an edge or a corner,
  // where the samples of several faces coincide): the nearest sample of each of up to 8 faces
  // starts a projection, the closest result is kept.
  parallel_for(np, [&](int j) {
    int tried[8] = {-1, -1, -1, -1, -1, -1, -1, -1};
    d[j] = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 8; ++k) {
      const ClosestPointTree::Hit h = tree.closest_if(points[j], [&](int e) {
        return std::find(tried, tried + k, where[e].ptex) == tried + k;
      });
      if (h.element < 0) break;
      PtexPoint at = where[h.element];
      tried[k] = at.ptex;
      const double dk = project(limit, points[j], at);
      if (dk < d[j]) {
        d[j] = dk;
        foot[j] = at;
      }
      if (k == 0 && (at.u > 0 && at.u < 1 && at.v > 0 && at.v < 1)) break;  // inside its face
    }
  });
  int worst = -1;
  DistanceStats s = summarise(d, diagonal, worst);
  if (worst >= 0) {
    s.where_ptex = foot[worst].ptex;
    s.where_u = foot[worst].u;
    s.where_v = foot[worst].v;
    s.where_target = worst;
  }
  return s;
}

TargetDistance measure_target_distance(const LimitEvaluator& limit, const ShapeTarget& target, int grid) {
  TargetDistance out;
  out.diagonal = target.diagonal();
  const std::vector<int> faces = surface_ptex(limit);
  std::vector<double> t(grid);
  for (int i = 0; i < grid; ++i) t[i] = (i + 0.5) / grid;
  std::vector<Point3> pos;
  std::vector<PtexPoint> where;
  sample_grid(limit, faces, t, pos, where);
  std::vector<double> d(pos.size());
  std::vector<int> element(pos.size());
  parallel_for(static_cast<int>(pos.size()), [&](int i) {
    const ShapeTarget::Closest c = target.closest(pos[i]);
    d[i] = c.distance;
    element[i] = c.element;
  });
  int worst = -1;
  out.limit_to_target = summarise(d, out.diagonal, worst);
  if (worst >= 0) {
    out.limit_to_target.where_ptex = where[worst].ptex;
    out.limit_to_target.where_u = where[worst].u;
    out.limit_to_target.where_v = where[worst].v;
    out.limit_to_target.where_target = element[worst];
  }
  out.target_to_limit = points_to_limit(limit, target.points(), out.diagonal, grid);
  return out;
}

}  // namespace subd2nurbs
