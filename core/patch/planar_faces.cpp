#include "core/patch/planar_faces.h"

#include <algorithm>
#include <array>
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
/// points inside every knot span): a planar patch can still fold over itself in its plane (a
/// sheet doubled back at its rim, a fitted quad slid over its neighbour). Counted, not refused:
/// the planar face is the region the set's loops enclose (find_planar_faces).
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
/// with holes bounded by simple loops. When the loops close but not exactly one of them turns
/// counter-clockwise (an overlap in the plane), `f.loops` holds them all the same (unordered).
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
  int outer = -1, ccw = 0;
  for (size_t i = 0; i < loops.size(); ++i)
    if (signed_area(ps, loops[i], f) > 0) outer = static_cast<int>(i), ++ccw;
  if (ccw == 1) std::swap(loops[0], loops[outer]);
  f.loops = std::move(loops);
  return ccw == 1;
}

using Point2 = std::array<double, 2>;

/// Twice the signed area of the triangle (a, b, c): > 0 when c is left of a -> b.
double orient(const Point2& a, const Point2& b, const Point2& c) {
  return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

}  // namespace

std::vector<int> crossing_curves(const PatchSet& ps, const PlanarFace& f) {
  // Every loop curve as a polyline in the plane's (x, y), 16 segments per curve.
  constexpr int kSegments = 16;
  const Point3 y_axis = cross(f.normal, f.x_axis);
  struct Polyline {
    int curve;
    std::vector<Point2> pts;
    Point2 lo, hi;  // bounding box
  };
  std::vector<Polyline> lines;
  double extent = 0;
  for (const auto& loop : f.loops)
    for (const LoopCurve& c : loop) {
      Polyline l{c.curve, {}, {HUGE_VAL, HUGE_VAL}, {-HUGE_VAL, -HUGE_VAL}};
      for (int k = 0; k <= kSegments; ++k) {
        const Point3 d = sub(evaluate(ps.curves[c.curve], static_cast<double>(k) / kSegments), f.origin);
        const Point2 q{dot(d, f.x_axis), dot(d, y_axis)};
        for (int i = 0; i < 2; ++i) {
          l.lo[i] = std::min(l.lo[i], q[i]);
          l.hi[i] = std::max(l.hi[i], q[i]);
          extent = std::max(extent, std::abs(q[i]));
        }
        l.pts.push_back(q);
      }
      lines.push_back(std::move(l));
    }
  // Two segments cross when each one's ends lie strictly on both sides of the other's line.
  // Segments that share an end (a curve's own consecutive segments, curves meeting at a corner)
  // only touch; rounding is kept out by a margin relative to the face's extent.
  const double eps = 1e-10 * extent * extent;
  const double same = 1e-10 * extent;
  auto close = [&](const Point2& a, const Point2& b) {
    return std::abs(a[0] - b[0]) <= same && std::abs(a[1] - b[1]) <= same;
  };
  auto cross_strictly = [&](const Point2& a, const Point2& b, const Point2& c, const Point2& d) {
    if (close(a, c) || close(a, d) || close(b, c) || close(b, d)) return false;
    const double o1 = orient(a, b, c), o2 = orient(a, b, d), o3 = orient(c, d, a), o4 = orient(c, d, b);
    return ((o1 > eps && o2 < -eps) || (o1 < -eps && o2 > eps)) && ((o3 > eps && o4 < -eps) || (o3 < -eps && o4 > eps));
  };
  std::vector<char> crossing(lines.size(), 0);
  for (size_t i = 0; i < lines.size(); ++i)
    for (size_t j = i; j < lines.size(); ++j) {
      const Polyline &A = lines[i], &B = lines[j];
      if (A.hi[0] < B.lo[0] || B.hi[0] < A.lo[0] || A.hi[1] < B.lo[1] || B.hi[1] < A.lo[1]) continue;
      bool found = false;
      for (int a = 0; a < kSegments && !found; ++a)
        for (int b = (i == j ? a + 2 : 0); b < kSegments && !found; ++b)
          found = cross_strictly(A.pts[a], A.pts[a + 1], B.pts[b], B.pts[b + 1]);
      if (found) crossing[i] = crossing[j] = 1;
    }
  std::vector<int> out;
  for (size_t i = 0; i < lines.size(); ++i)
    if (crossing[i]) out.push_back(lines[i].curve);
  // A loop that turns back on itself at a corner (a cusp: the curves leave the corner along the
  // same line) runs along itself there: OCCT finds its curves intersecting beside the corner.
  constexpr double kCusp = 150.0 * M_PI / 180.0;
  for (const auto& loop : f.loops)
    for (size_t i = 0; i < loop.size(); ++i) {
      const LoopCurve& in = loop[i];
      const LoopCurve& next = loop[(i + 1) % loop.size()];
      if (std::abs(left_turn(ps, in, next, f.normal)) > kCusp) {
        out.push_back(in.curve);
        out.push_back(next.curve);
      }
    }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

namespace {

/// Per patch, the patches that share a curve with it, among those `in` marks.
std::vector<std::vector<int>> curve_neighbours(const PatchSet& ps, const std::vector<char>& in) {
  std::vector<std::vector<int>> neighbours(ps.patches.size());
  for (const BoundaryCurve& c : ps.curves)
    for (const CurveUse& a : c.uses)
      for (const CurveUse& b : c.uses)
        if (a.patch != b.patch && in[a.patch] && in[b.patch]) neighbours[a.patch].push_back(b.patch);
  return neighbours;
}

/// The patches reached breadth first from `seed` across `neighbours` that `accept` admits (not
/// yet `reached`: marked as they are reached), ascending.
template <class Accept>
std::vector<int> grow(int seed, const std::vector<std::vector<int>>& neighbours, std::vector<char>& reached,
                      Accept&& accept) {
  std::vector<int> set;
  std::deque<int> queue{seed};
  reached[seed] = 1;
  while (!queue.empty()) {
    const int p = queue.front();
    queue.pop_front();
    set.push_back(p);
    for (int q : neighbours[p]) {
      if (reached[q] || !accept(q)) continue;
      reached[q] = 1;
      queue.push_back(q);
    }
  }
  std::sort(set.begin(), set.end());
  return set;
}

/// Adds the set `f` (its plane set, its loops not yet made) to `out` as one planar face when its
/// boundary is one region with holes. When its loops close but are not that (more than one
/// outer loop: patches overlapping in the plane), it is split at the crossings of its loops
/// (split_at_crossings), up to `depth` rounds. Returns the number of sets it gave up on.
int add_regions(const PatchSet& ps, PlanarFace f, int depth, std::vector<PlanarFace>& out, int& split);

/// The connected parts of `f.patches` left when the patches along the crossing curves `bad` are
/// left out, each added by add_regions. Returns the number of parts it gave up on.
int split_at_crossings(const PatchSet& ps, const PlanarFace& f, const std::vector<int>& bad, int depth,
                       std::vector<PlanarFace>& out, int& split) {
  ++split;
  std::vector<char> dropped_curve(ps.curves.size(), 0);
  for (int k : bad) dropped_curve[k] = 1;
  std::vector<int> keep;
  for (int p : f.patches) {
    bool on_bad = false;
    for (const LoopCurve& c : boundary_pieces(ps.patches[p])) on_bad = on_bad || dropped_curve[c.curve];
    if (!on_bad) keep.push_back(p);
  }
  // Connected parts of the rest, across curves two of them share.
  std::vector<char> kept(ps.patches.size(), 0);
  for (int p : keep) kept[p] = 1;
  const std::vector<std::vector<int>> neighbours = curve_neighbours(ps, kept);
  std::vector<char> reached(ps.patches.size(), 0);
  int gave_up = 0;
  for (int seed : keep) {
    if (reached[seed]) continue;
    PlanarFace part;  // f's plane
    part.origin = f.origin;
    part.normal = f.normal;
    part.x_axis = f.x_axis;
    part.tolerance = f.tolerance;
    part.patches = grow(seed, neighbours, reached, [](int) { return true; });
    gave_up += add_regions(ps, std::move(part), depth, out, split);
  }
  return gave_up;
}

int add_regions(const PatchSet& ps, PlanarFace f, int depth, std::vector<PlanarFace>& out, int& split) {
  if (make_loops(ps, f, f.tolerance)) {
    out.push_back(std::move(f));
    return 0;
  }
  if (f.loops.empty() || depth == 0) return 1;
  const std::vector<int> bad = crossing_curves(ps, f);
  if (bad.empty()) return 1;
  return split_at_crossings(ps, f, bad, depth - 1, out, split);
}

constexpr int kMaxSplits = 4;  // rounds of leaving out the patches along crossing curves

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
    planar[p] = on_plane(patch, origin[p], normal[p], tolerance);
    out.planar_patches += planar[p];
  }
  out.folded_patch.assign(n, 0);
  // Neighbours across shared curves, grown breadth first from the lowest patch of each set.
  const std::vector<std::vector<int>> neighbours = curve_neighbours(ps, planar);
  std::vector<char> reached(n, 0);
  for (int seed = 0; seed < n; ++seed) {
    if (!planar[seed] || reached[seed]) continue;
    PlanarFace f;
    f.patches = grow(seed, neighbours, reached, [&](int q) {
      return dot(normal[q], normal[seed]) > 0 && on_plane(ps.patches[q], origin[seed], normal[seed], tolerance);
    });
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
    if (!flat) {
      ++out.skipped;
      continue;
    }
    f.tolerance = tolerance.of(f.normal);
    for (int p : f.patches) out.folded_patch[p] = !unfolded(ps.patches[p], f.normal);
    std::vector<PlanarFace> regions;
    out.skipped += add_regions(ps, std::move(f), kMaxSplits, regions, out.split);
    for (PlanarFace& r : regions) {
      const int index = static_cast<int>(out.faces.size());
      for (int p : r.patches) out.face_of_patch[p] = index;
      out.faces.push_back(std::move(r));
    }
  }
  return out;
}

std::vector<PlanarFace> split_planar_face(const PatchSet& ps, const PlanarFace& f, const std::vector<int>& also) {
  std::vector<PlanarFace> out;
  std::vector<int> bad = crossing_curves(ps, f);
  bad.insert(bad.end(), also.begin(), also.end());
  if (bad.empty()) return out;
  int split = 0;
  split_at_crossings(ps, f, bad, kMaxSplits, out, split);
  return out;
}

}  // namespace subd2nurbs
