#include "core/fit/shape_target.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

#include "core/util/vec3.h"

namespace subd2nurbs {
namespace {

using vec3::sub;
using vec3::dot;
using vec3::cross;
using vec3::axpy;
using vec3::dist2;

double box_distance2(const Point3& q, const Point3& lo, const Point3& hi) {
  double d2 = 0;
  for (int k = 0; k < 3; ++k) {
    const double d = q[k] < lo[k] ? lo[k] - q[k] : (q[k] > hi[k] ? q[k] - hi[k] : 0.0);
    d2 += d * d;
  }
  return d2;
}

}  // namespace

Point3 closest_point_on_triangle(const Point3& p, const Point3& a, const Point3& b, const Point3& c) {
  const Point3 ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Point3 bp = sub(p, b);
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return axpy(a, d1 / (d1 - d3), ab);
  const Point3 cp = sub(p, c);
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return axpy(a, d2 / (d2 - d6), ac);
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return axpy(b, (d4 - d3) / ((d4 - d3) + (d5 - d6)), sub(c, b));
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  return axpy(axpy(a, v, ab), w, ac);
}

std::array<double, 3> barycentric(const Point3& p, const Point3& a, const Point3& b, const Point3& c) {
  const Point3 v0 = sub(b, a), v1 = sub(c, a), v2 = sub(p, a);
  const double d00 = dot(v0, v0), d01 = dot(v0, v1), d11 = dot(v1, v1), d20 = dot(v2, v0), d21 = dot(v2, v1);
  const double denom = d00 * d11 - d01 * d01;
  if (!(denom > 0)) return {1, 0, 0};
  const double y = (d11 * d20 - d01 * d21) / denom, z = (d00 * d21 - d01 * d20) / denom;
  return {1 - y - z, y, z};
}

ClosestPointTree::ClosestPointTree(const std::vector<Point3>& points, const std::vector<std::array<int, 3>>& triangles)
    : pts_(points), tris_(triangles) {
  const int n = static_cast<int>(tris_.empty() ? pts_.size() : tris_.size());
  if (n == 0) return;
  std::vector<Point3> centre(n);
  prim_box_.resize(n);
  for (int i = 0; i < n; ++i) {
    if (tris_.empty()) {
      prim_box_[i] = {pts_[i], pts_[i]};
      centre[i] = pts_[i];
      continue;
    }
    Point3 lo = pts_[tris_[i][0]], hi = lo;
    for (int k = 1; k < 3; ++k)
      for (int c = 0; c < 3; ++c) {
        lo[c] = std::min(lo[c], pts_[tris_[i][k]][c]);
        hi[c] = std::max(hi[c], pts_[tris_[i][k]][c]);
      }
    prim_box_[i] = {lo, hi};
    for (int c = 0; c < 3; ++c) centre[i][c] = 0.5 * (lo[c] + hi[c]);
  }
  order_.resize(n);
  std::iota(order_.begin(), order_.end(), 0);
  nodes_.reserve(2 * (n / 4 + 1));
  build(0, n, centre);
}

int ClosestPointTree::build(int first, int count, const std::vector<Point3>& centre) {
  const int id = static_cast<int>(nodes_.size());
  nodes_.push_back({});
  Point3 lo = prim_box_[order_[first]][0], hi = prim_box_[order_[first]][1];
  Point3 clo = centre[order_[first]], chi = clo;
  for (int i = first; i < first + count; ++i)
    for (int c = 0; c < 3; ++c) {
      lo[c] = std::min(lo[c], prim_box_[order_[i]][0][c]);
      hi[c] = std::max(hi[c], prim_box_[order_[i]][1][c]);
      clo[c] = std::min(clo[c], centre[order_[i]][c]);
      chi[c] = std::max(chi[c], centre[order_[i]][c]);
    }
  nodes_[id].lo = lo;
  nodes_[id].hi = hi;
  if (count <= 4) {
    nodes_[id].first = first;
    nodes_[id].count = count;
    return id;
  }
  int axis = 0;
  for (int c = 1; c < 3; ++c)
    if (chi[c] - clo[c] > chi[axis] - clo[axis]) axis = c;
  const int half = count / 2;
  std::nth_element(order_.begin() + first, order_.begin() + first + half, order_.begin() + first + count,
                   [&](int a, int b) { return centre[a][axis] < centre[b][axis]; });
  const int left = build(first, half, centre);
  const int right = build(first + half, count - half, centre);
  nodes_[id].left = left;
  nodes_[id].right = right;
  return id;
}

ClosestPointTree::Hit ClosestPointTree::closest(const Point3& q, int hint) const {
  Hit best;
  best.distance2 = std::numeric_limits<double>::infinity();
  if (hint >= 0 && hint < static_cast<int>(order_.size())) {
    best.point = primitive_point(q, hint);
    best.distance2 = dist2(best.point, q);
    best.element = hint;
  }
  search(q, [](int) { return true; }, best);
  return best;
}

ClosestPointTree::Hit ClosestPointTree::closest_if(const Point3& q, const std::function<bool(int)>& accept) const {
  Hit best;
  best.distance2 = std::numeric_limits<double>::infinity();
  if (accept) search(q, accept, best);
  else search(q, [](int) { return true; }, best);
  return best;
}

Point3 ClosestPointTree::primitive_point(const Point3& q, int e) const {
  return tris_.empty() ? pts_[e] : closest_point_on_triangle(q, pts_[tris_[e][0]], pts_[tris_[e][1]], pts_[tris_[e][2]]);
}

template <class Accept>
void ClosestPointTree::search(const Point3& q, const Accept& accept, Hit& best) const {
  if (nodes_.empty()) return;
  int stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (box_distance2(q, node.lo, node.hi) >= best.distance2) continue;
    if (node.left < 0) {
      for (int i = node.first; i < node.first + node.count; ++i) {
        const int e = order_[i];
        if (!accept(e)) continue;
        const Point3 p = primitive_point(q, e);
        const double d2 = dist2(p, q);
        if (d2 < best.distance2 || (d2 == best.distance2 && e < best.element)) best = {p, d2, e};
      }
      continue;
    }
    const double dl = box_distance2(q, nodes_[node.left].lo, nodes_[node.left].hi);
    const double dr = box_distance2(q, nodes_[node.right].lo, nodes_[node.right].hi);
    // Push the farther child first so the nearer one is searched first.
    if (dl <= dr) {
      stack[top++] = node.right;
      stack[top++] = node.left;
    } else {
      stack[top++] = node.left;
      stack[top++] = node.right;
    }
  }
}

ShapeTarget::ShapeTarget(std::vector<Point3> points, std::vector<std::array<int, 3>> triangles,
                         std::vector<Point3> normals, int triangle_samples)
    : points_(std::move(points)), triangles_(std::move(triangles)) {
  if (points_.empty()) throw std::invalid_argument("ShapeTarget: no points");
  const int np = static_cast<int>(points_.size());
  for (const auto& t : triangles_)
    for (int k : t)
      if (k < 0 || k >= np) throw std::invalid_argument("ShapeTarget: triangle index out of range");
  if (!normals.empty() && static_cast<int>(normals.size()) != np)
    throw std::invalid_argument("ShapeTarget: one normal per point expected");
  Point3 lo = points_[0], hi = lo;
  for (const Point3& p : points_)
    for (int c = 0; c < 3; ++c) {
      lo[c] = std::min(lo[c], p[c]);
      hi[c] = std::max(hi[c], p[c]);
    }
  diagonal_ = std::sqrt(dist2(lo, hi));
  data_points_ = points_;
  if (triangles_.empty()) {
    normals_ = std::move(normals);
  } else {
    normals_.assign(points_.size(), Point3{0, 0, 0});
    for (size_t i = 0; i < triangles_.size(); ++i) {
      const Point3 &a = points_[triangles_[i][0]], &b = points_[triangles_[i][1]], &c = points_[triangles_[i][2]];
      const Point3 n = cross(sub(b, a), sub(c, a));  // twice the area times the unit normal
      for (int k : triangles_[i])
        for (int d = 0; d < 3; ++d) normals_[k][d] += n[d];
      if (triangle_samples <= 0) continue;
      const Point3 g = {(a[0] + b[0] + c[0]) / 3, (a[1] + b[1] + c[1]) / 3, (a[2] + b[2] + c[2]) / 3};
      data_points_.push_back(g);
      if (triangle_samples >= 3)
        for (const Point3* v : {&a, &b, &c})
          data_points_.push_back({0.5 * (g[0] + (*v)[0]), 0.5 * (g[1] + (*v)[1]), 0.5 * (g[2] + (*v)[2])});
    }
  }
  for (Point3& n : normals_) {
    const double len = std::sqrt(dot(n, n));
    if (len > 0)
      for (double& c : n) c /= len;
  }
  tree_ = ClosestPointTree(points_, triangles_);
}

ShapeTarget::Closest ShapeTarget::closest(const Point3& q, int hint) const {
  const ClosestPointTree::Hit h = tree_.closest(q, hint);
  Closest out;
  out.point = h.point;
  out.distance = std::sqrt(h.distance2);
  out.element = h.element;
  if (h.element < 0 || normals_.empty()) return out;
  if (triangles_.empty()) {
    out.normal = normals_[h.element];
    return out;
  }
  const std::array<int, 3>& t = triangles_[h.element];
  const std::array<double, 3> w = barycentric(h.point, points_[t[0]], points_[t[1]], points_[t[2]]);
  Point3 n{0, 0, 0};
  for (int k = 0; k < 3; ++k)
    for (int d = 0; d < 3; ++d) n[d] += w[k] * normals_[t[k]][d];
  const double len = std::sqrt(dot(n, n));
  if (len > 0)
    for (double& c : n) c /= len;
  out.normal = n;
  return out;
}

}  // namespace subd2nurbs
