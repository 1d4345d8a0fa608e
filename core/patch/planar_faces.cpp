#include "core/patch/planar_faces.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <map>

#include "core/nurbs/nurbs_eval.h"
#include "core/util/vec3.h"

namespace subd2nurbs {

namespace {

using vec3::cross;
using vec3::dot;
using vec3::norm;
using vec3::sub;

Point3 add(const Point3& a, const Point3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
Point3 scaled(const Point3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }

/// The sum of the control net's cell cross products: for a planar net, a normal of the plane
/// pointing the way X_u x X_v does, of length twice the net's area.
Point3 net_normal(const NurbsPatch& p) {
  Point3 n{0, 0, 0};
  for (int i = 0; i + 1 < p.num_poles_u; ++i)
    for (int j = 0; j + 1 < p.num_poles_v; ++j) {
      // The cell's diagonals' cross product: twice its vector area, whatever its shape.
      const Point3 d0 = sub(p.pole(i + 1, j + 1), p.pole(i, j));
      const Point3 d1 = sub(p.pole(i, j + 1), p.pole(i + 1, j));
      n = add(n, cross(d0, d1));
    }
  return n;
}

Point3 pole_mean(const NurbsPatch& p) {
  Point3 m{0, 0, 0};
  for (const Point3& q : p.poles) m = add(m, q);
  return scaled(m, 1.0 / std::max<size_t>(1, p.poles.size()));
}

/// How far a pole may be from a plane and still be on it: rounding, which scales with the
/// coordinates' magnitudes along the plane's normal (a part 1e8 long and 1e-8 thin has planes
/// that must be told apart at 1e-20, not at 1e-12 of its size).
struct PlaneTolerance {
  double relative = 0, cap = 0;
  Point3 scale{};  ///< per axis: the largest |coordinate| of any pole
  double of(const Point3& n) const {
    return std::min(cap, relative * (std::abs(n[0]) * scale[0] + std::abs(n[1]) * scale[1] + std::abs(n[2]) * scale[2]));
  }
};

bool on_plane(const NurbsPatch& p, const Point3& origin, const Point3& normal, const PlaneTolerance& t) {
  const double tolerance = t.of(normal);
  for (const Point3& q : p.poles)
    if (std::abs(dot(sub(q, origin), normal)) > tolerance) return false;
  return true;
}

/// Whether the patch's normal X_u x X_v points along `normal` all over it (sampled at 4 x 4
/// points inside every knot span): a planar patch can still fold over itself (a sheet
/// doubled back at its rim), and a folded patch is not the region its boundary encloses.
bool unfolded(const NurbsPatch& p, const Point3& normal) {
  const PatchEvaluator eval(p);
  const auto& U = p.knots_u.knots;
  const auto& V = p.knots_v.knots;
  constexpr int kSamples = 4;
  for (size_t i = 0; i + 1 < U.size(); ++i)
    for (size_t j = 0; j + 1 < V.size(); ++j)
      for (int a = 0; a < kSamples; ++a)
        for (int b = 0; b < kSamples; ++b) {
          const double u = U[i] + (a + 0.5) / kSamples * (U[i + 1] - U[i]);
          const double v = V[j] + (b + 0.5) / kSamples * (V[j + 1] - V[j]);
          const SurfaceDerivs d = eval.derivs(u, v, 1);
          if (!(dot(cross(d.du, d.dv), normal) > 0)) return false;
        }
  return true;
}

/// The oriented curve pieces of a patch's boundary, counter-clockwise (collapsed sides have none).
std::vector<LoopCurve> boundary_pieces(const NurbsPatch& p) {
  std::vector<LoopCurve> out;
  for (int side = 0; side < 4; ++side) {
    if (p.curves[side] >= 0) {
      out.push_back({p.curves[side], p.curve_reversed[side]});
      continue;
    }
    for (const SidePiece& q : p.split_sides[side]) out.push_back({q.curve, q.reversed});
  }
  return out;
}

int start_corner(const PatchSet& ps, const LoopCurve& c) {
  return c.reversed ? ps.curves[c.curve].corner1 : ps.curves[c.curve].corner0;
}
int end_corner(const PatchSet& ps, const LoopCurve& c) {
  return c.reversed ? ps.curves[c.curve].corner0 : ps.curves[c.curve].corner1;
}

/// The curve's direction leaving its start (end = false) or arriving at its end, as traversed.
Point3 end_direction(const BoundaryCurve& c, bool reversed, bool end) {
  const auto& P = c.poles;
  const size_t n = P.size();
  const bool at_last = end != reversed;  // the curve's own last pole
  const Point3& a = at_last ? P[n - 1] : P[0];
  for (size_t k = 1; k < n; ++k) {  // the first pole that differs from the end one
    const Point3 d = at_last ? sub(a, P[n - 1 - k]) : sub(P[k], a);
    if (norm(d) > 0) return reversed ? scaled(d, -1) : d;
  }
  return {0, 0, 0};
}

/// The angle (-pi .. pi] by which the boundary turns left (about `normal`) from `in` into `out`.
double left_turn(const PatchSet& ps, const LoopCurve& in, const LoopCurve& out, const Point3& normal) {
  const Point3 a = end_direction(ps.curves[in.curve], in.reversed, true);
  const Point3 b = end_direction(ps.curves[out.curve], out.reversed, false);
  return std::atan2(dot(cross(a, b), normal), dot(a, b));
}

/// Signed area of a loop in the plane's (x, y) coordinates, the curves sampled at 16 points each.
double signed_area(const PatchSet& ps, const std::vector<LoopCurve>& loop, const PlanarFace& f) {
  const Point3 y_axis = cross(f.normal, f.x_axis);
  std::vector<std::array<double, 2>> pts;
  constexpr int kSamples = 16;
  for (const LoopCurve& c : loop)
    for (int k = 0; k < kSamples; ++k) {
      const double s = static_cast<double>(k) / kSamples;
      const Point3 d = sub(evaluate(ps.curves[c.curve], c.reversed ? 1 - s : s), f.origin);
      pts.push_back({dot(d, f.x_axis), dot(d, y_axis)});
    }
  double a = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    const auto& p = pts[i];
    const auto& q = pts[(i + 1) % pts.size()];
    a += p[0] * q[1] - q[0] * p[1];
  }
  return a / 2;
}

/// The boundary loops of the set `f.patches` (outer first), or false when it is not one region
/// with holes bounded by simple loops.
bool make_loops(const PatchSet& ps, PlanarFace& f, double tolerance) {  // model units
  // Curves used once inside the set bound it; curves used twice (both ways) are inside it.
  std::map<int, std::vector<LoopCurve>> uses;
  for (int p : f.patches)
    for (const LoopCurve& c : boundary_pieces(ps.patches[p])) uses[c.curve].push_back(c);
  std::vector<LoopCurve> boundary;
  std::multimap<int, int> from;  // start corner -> the boundary curves leaving it
  for (const auto& [k, list] : uses) {
    if (list.size() == 2 && list[0].reversed != list[1].reversed) continue;
    if (list.size() != 1) return false;
    for (const Point3& q : ps.curves[k].poles)
      if (std::abs(dot(sub(q, f.origin), f.normal)) > tolerance) return false;
    from.emplace(start_corner(ps, list[0]), static_cast<int>(boundary.size()));
    boundary.push_back(list[0]);
  }
  if (boundary.empty()) return false;
  // Loops: from each unused curve, on to the next curve leaving the corner it ends at. Where the
  // boundary passes a corner twice (a hole touching the outer loop there), the next curve is
  // the one turning most to the right: the walk then stays on its own loop (the region on its
  // left), so the outer loop and the hole come out as two simple loops sharing that corner.
  std::vector<std::vector<LoopCurve>> loops;
  std::vector<char> used(boundary.size(), 0);
  for (size_t first = 0; first < boundary.size(); ++first) {
    if (used[first]) continue;
    std::vector<LoopCurve> loop{boundary[first]};
    used[first] = 1;
    const int start = start_corner(ps, boundary[first]);
    while (true) {
      const LoopCurve& last = loop.back();
      const int corner = end_corner(ps, last);
      int next = -1;
      double best_turn = 10;
      for (auto [it, end] = from.equal_range(corner); it != end; ++it) {
        if (used[it->second] && !(corner == start && it->second == static_cast<int>(first))) continue;
        const double turn = left_turn(ps, last, boundary[it->second], f.normal);
        if (turn < best_turn) best_turn = turn, next = it->second;
      }
      if (next < 0) return false;  // an open chain: not a closed boundary
      if (next == static_cast<int>(first)) break;
      used[next] = 1;
      loop.push_back(boundary[next]);
    }
    loops.push_back(std::move(loop));
  }
  // Exactly one loop turns counter-clockwise about the normal (the outer one), the others are holes.
  int outer = -1;
  for (size_t i = 0; i < loops.size(); ++i) {
    if (signed_area(ps, loops[i], f) > 0) {
      if (outer >= 0) return false;
      outer = static_cast<int>(i);
    }
  }
  if (outer < 0) return false;
  std::swap(loops[0], loops[outer]);
  f.loops = std::move(loops);
  return true;
}

}  // namespace

PlanarFaces find_planar_faces(const PatchSet& ps, double relative_tolerance) {
  const int n = static_cast<int>(ps.patches.size());
  PlanarFaces out;
  PlaneTolerance tolerance;
  tolerance.relative = relative_tolerance;
  tolerance.cap = relative_tolerance * ps.model_size;
  for (const NurbsPatch& patch : ps.patches)
    for (const Point3& q : patch.poles)
      for (int i = 0; i < 3; ++i) tolerance.scale[i] = std::max(tolerance.scale[i], std::abs(q[i]));
  out.face_of_patch.assign(n, -1);
  // Per patch: its plane, when its poles lie on one.
  std::vector<Point3> origin(n), net(n), normal(n);
  std::vector<char> planar(n, 0);
  for (int p = 0; p < n; ++p) {
    const NurbsPatch& patch = ps.patches[p];
    net[p] = net_normal(patch);
    const double len = norm(net[p]);
    if (!(len > 0)) continue;
    origin[p] = pole_mean(patch);
    normal[p] = scaled(net[p], 1 / len);
    planar[p] = on_plane(patch, origin[p], normal[p], tolerance) && unfolded(patch, normal[p]);
    out.planar_patches += planar[p];
  }
  // Neighbours across shared curves, grown breadth first from the lowest patch of each set.
  std::vector<std::vector<int>> neighbours(n);
  for (const BoundaryCurve& c : ps.curves)
    for (const CurveUse& a : c.uses)
      for (const CurveUse& b : c.uses)
        if (a.patch != b.patch && planar[a.patch] && planar[b.patch]) neighbours[a.patch].push_back(b.patch);
  std::vector<char> reached(n, 0);
  for (int seed = 0; seed < n; ++seed) {
    if (!planar[seed] || reached[seed]) continue;
    PlanarFace f;
    std::deque<int> queue{seed};
    reached[seed] = 1;
    while (!queue.empty()) {
      const int p = queue.front();
      queue.pop_front();
      f.patches.push_back(p);
      for (int q : neighbours[p]) {
        if (reached[q] || dot(normal[q], normal[seed]) <= 0) continue;
        if (!on_plane(ps.patches[q], origin[seed], normal[seed], tolerance)) continue;
        reached[q] = 1;
        queue.push_back(q);
      }
    }
    std::sort(f.patches.begin(), f.patches.end());
    // The set's plane: the mean of its poles, the sum of its nets' normals.
    Point3 sum{0, 0, 0}, nsum{0, 0, 0};
    size_t count = 0;
    for (int p : f.patches) {
      for (const Point3& q : ps.patches[p].poles) sum = add(sum, q);
      count += ps.patches[p].poles.size();
      nsum = add(nsum, net[p]);
    }
    f.origin = scaled(sum, 1.0 / static_cast<double>(count));
    f.normal = scaled(nsum, 1 / norm(nsum));
    const Point3 helper = std::abs(f.normal[0]) < 0.6 ? Point3{1, 0, 0} : Point3{0, 1, 0};
    const Point3 x = cross(helper, f.normal);
    f.x_axis = scaled(x, 1 / norm(x));
    bool flat = true;
    for (int p : f.patches) flat = flat && on_plane(ps.patches[p], f.origin, f.normal, tolerance);
    if (!flat || !make_loops(ps, f, tolerance.of(f.normal))) {
      ++out.skipped;
      continue;
    }
    const int index = static_cast<int>(out.faces.size());
    for (int p : f.patches) out.face_of_patch[p] = index;
    out.faces.push_back(std::move(f));
  }
  return out;
}

}  // namespace subd2nurbs
