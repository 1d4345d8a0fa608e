// Hand-built PatchSets with known answers, for testing the OCCT front end without the patch
// builder: a unit cube of planar patches, a B-spline torus split into any grid of patches,
// one open patch, one patch with a collapsed side.
#pragma once

#include <cmath>
#include <functional>
#include <map>
#include <utility>
#include <vector>

#include "core/nurbs/patch_set.h"

namespace subd2nurbs::testing {

/// Clamped cubic knots over [0, 1] with `spans` uniform spans: 0 (x4), 1/spans, ..., 1 (x4).
inline KnotVector clamped_knots(int spans) {
  KnotVector kv;
  for (int k = 0; k <= spans; ++k) {
    kv.knots.push_back(static_cast<double>(k) / spans);
    kv.mults.push_back(k == 0 || k == spans ? 4 : 1);
  }
  return kv;
}

/// A bicubic patch with `spans_u` x `spans_v` uniform spans and poles from `pole(i, j)`.
inline NurbsPatch make_patch(int spans_u, int spans_v,
                             const std::function<Point3(int, int)>& pole) {
  NurbsPatch p;
  p.knots_u = clamped_knots(spans_u);
  p.knots_v = clamped_knots(spans_v);
  p.num_poles_u = spans_u + 3;
  p.num_poles_v = spans_v + 3;
  p.poles.resize(static_cast<size_t>(p.num_poles_u) * p.num_poles_v);
  for (int i = 0; i < p.num_poles_u; ++i)
    for (int j = 0; j < p.num_poles_v; ++j) p.pole(i, j) = pole(i, j);
  return p;
}

/// Poles of side `side` of `p` in the counter-clockwise direction of that side.
inline std::vector<Point3> side_poles(const NurbsPatch& p, int side) {
  std::vector<Point3> out;
  const int nu = p.num_poles_u, nv = p.num_poles_v;
  switch (side) {
    case 0: for (int i = 0; i < nu; ++i) out.push_back(p.pole(i, 0)); break;
    case 1: for (int j = 0; j < nv; ++j) out.push_back(p.pole(nu - 1, j)); break;
    case 2: for (int i = nu - 1; i >= 0; --i) out.push_back(p.pole(i, nv - 1)); break;
    case 3: for (int j = nv - 1; j >= 0; --j) out.push_back(p.pole(0, j)); break;
  }
  return out;
}

/// The knot vector of side `side`, in the counter-clockwise direction (mirrored for sides 2
/// and 3, which run towards decreasing u or v).
inline KnotVector side_knots(const NurbsPatch& p, int side) {
  const KnotVector& kv = side % 2 == 0 ? p.knots_u : p.knots_v;
  if (side < 2) return kv;
  KnotVector out;
  const double a = kv.knots.front(), b = kv.knots.back();
  for (size_t k = kv.knots.size(); k-- > 0;) {
    out.knots.push_back(a + b - kv.knots[k]);
    out.mults.push_back(kv.mults[k]);
  }
  return out;
}

/// Adds a curve that is side `side` of patch `p`, run the way the side runs (so this use is
/// not reversed), and records the use. Returns the curve index.
inline int add_curve_from_side(PatchSet& ps, int p, int side, Continuity continuity) {
  NurbsPatch& patch = ps.patches[p];
  BoundaryCurve c;
  c.corner0 = patch.corners[side];
  c.corner1 = patch.corners[(side + 1) % 4];
  c.knots = side_knots(patch, side);
  c.poles = side_poles(patch, side);
  c.continuity = continuity;
  c.uses.push_back({p, side, false});
  ps.curves.push_back(c);
  const int k = static_cast<int>(ps.curves.size()) - 1;
  patch.curves[side] = k;
  patch.curve_reversed[side] = false;
  return k;
}

/// Records that side `side` of patch `p` is curve `k`, traversed against the curve's direction
/// when `reversed`.
inline void attach(PatchSet& ps, int p, int side, int k, bool reversed) {
  ps.patches[p].curves[side] = k;
  ps.patches[p].curve_reversed[side] = reversed;
  ps.curves[k].uses.push_back({p, side, reversed});
  if (ps.curves[k].uses.size() == 2 && ps.curves[k].continuity == Continuity::Boundary)
    ps.curves[k].continuity = Continuity::C0;
}

/// Fills the curves of patches whose corners are set and whose sides are told apart by their
/// corner pairs (true when no two sides join the same two corners): the first side met makes
/// the curve, the second uses it.
inline void connect_by_corner_pairs(PatchSet& ps, Continuity shared) {
  std::map<std::pair<int, int>, int> curve_of;
  for (int p = 0; p < static_cast<int>(ps.patches.size()); ++p)
    for (int side = 0; side < 4; ++side) {
      const int a = ps.patches[p].corners[side], b = ps.patches[p].corners[(side + 1) % 4];
      const auto key = std::minmax(a, b);
      const auto found = curve_of.find(key);
      if (found == curve_of.end()) {
        curve_of[key] = add_curve_from_side(ps, p, side, Continuity::Boundary);
      } else {
        attach(ps, p, side, found->second, ps.curves[found->second].corner0 != a);
        ps.curves[found->second].continuity = shared;
      }
    }
  ps.closed = true;
  for (const BoundaryCurve& c : ps.curves) ps.closed = ps.closed && c.uses.size() == 2;
}

inline Point3 lerp3(const Point3& a, const Point3& b, const Point3& c, double s, double t) {
  // a + s (b - a) + t (c - a)
  return {a[0] + s * (b[0] - a[0]) + t * (c[0] - a[0]), a[1] + s * (b[1] - a[1]) + t * (c[1] - a[1]),
          a[2] + s * (b[2] - a[2]) + t * (c[2] - a[2])};
}

/// The unit cube [0,1]^3 as six planar bicubic patches (poles on a regular 4x4 grid), with
/// outward normals, or all inward when `inward` (the cage of a reversed cube).
inline PatchSet unit_cube(bool inward = false) {
  PatchSet ps;
  for (int c = 0; c < 8; ++c)
    ps.corners.push_back({{double(c & 1), double((c >> 1) & 1), double((c >> 2) & 1)}, c});
  // Corners of each face, counter-clockwise seen from outside.
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces) {
    std::array<int, 4> c{{f[0], f[1], f[2], f[3]}};
    if (inward) c = {{f[0], f[3], f[2], f[1]}};
    const Point3 o = ps.corners[c[0]].position, u = ps.corners[c[1]].position,
                 v = ps.corners[c[3]].position;
    NurbsPatch p = make_patch(1, 1, [&](int i, int j) { return lerp3(o, u, v, i / 3.0, j / 3.0); });
    p.corners = c;
    p.base_faces = {static_cast<int>(ps.patches.size())};
    ps.patches.push_back(p);
  }
  connect_by_corner_pairs(ps, Continuity::C0);
  ps.model_size = std::sqrt(3.0);
  return ps;
}

/// §6.3 of MATH.md: the clamped form of a uniform cubic B-spline with control points
/// P_0..P_{m+2} (P_i <-> blossom f(i-2, i-1, i)), m spans; m + 3 poles over knots 0..m.
inline std::vector<Point3> clamp_uniform(const std::vector<Point3>& P) {
  const int m = static_cast<int>(P.size()) - 3;
  auto comb = [](const Point3& a, double wa, const Point3& b, double wb, const Point3& c,
                 double wc, double div) {
    return Point3{(wa * a[0] + wb * b[0] + wc * c[0]) / div, (wa * a[1] + wb * b[1] + wc * c[1]) / div,
                  (wa * a[2] + wb * b[2] + wc * c[2]) / div};
  };
  std::vector<Point3> D(P.size());
  D[0] = comb(P[0], 1, P[1], 4, P[2], 1, 6);
  D[1] = comb(P[1], 2, P[2], 1, P[2], 0, 3);
  for (int k = 2; k <= m; ++k) D[k] = P[k];
  D[m + 1] = comb(P[m], 1, P[m + 1], 2, P[m + 1], 0, 3);
  D[m + 2] = comb(P[m], 1, P[m + 1], 4, P[m + 2], 1, 6);
  return D;
}

/// A uniform periodic bicubic B-spline on a torus control net (grid_u x grid_v points on a
/// torus with radii 3 and 1, u around the axis, v around the tube), split into
/// patches_u x patches_v clamped patches (grid sizes divisible by the patch counts). Normals
/// point outward. All curves are C2. With 1 x 1 patches the single face has two seams.
inline PatchSet bspline_torus(int patches_u, int patches_v, int grid_u = 8, int grid_v = 6) {
  const double R = 3, r = 1, pi = std::acos(-1.0);
  auto net = [&](int a, int b) {
    a = ((a % grid_u) + grid_u) % grid_u;
    b = ((b % grid_v) + grid_v) % grid_v;
    const double th = 2 * pi * a / grid_u, ph = 2 * pi * b / grid_v;
    return Point3{(R + r * std::cos(ph)) * std::cos(th), (R + r * std::cos(ph)) * std::sin(th),
                  r * std::sin(ph)};
  };
  const int mu = grid_u / patches_u, mv = grid_v / patches_v;
  auto wrap_u = [&](int a) { return ((a % patches_u) + patches_u) % patches_u; };
  auto wrap_v = [&](int b) { return ((b % patches_v) + patches_v) % patches_v; };
  auto patch_index = [&](int a, int b) { return wrap_u(a) * patches_v + wrap_v(b); };

  PatchSet ps;
  for (int a = 0; a < patches_u; ++a)
    for (int b = 0; b < patches_v; ++b) {
      // Rows along u first (one per net column), then along v: neighbours compute their
      // shared boundary poles with the same operations, so they agree to the last bit.
      std::vector<std::vector<Point3>> rows(mu + 3);  // rows[i][col]
      for (int col = 0; col < mv + 3; ++col) {
        std::vector<Point3> P;
        for (int i = 0; i < mu + 3; ++i) P.push_back(net(a * mu - 1 + i, b * mv - 1 + col));
        const std::vector<Point3> D = clamp_uniform(P);
        for (int i = 0; i < mu + 3; ++i) rows[i].push_back(D[i]);
      }
      for (auto& row : rows) row = clamp_uniform(row);
      NurbsPatch p = make_patch(mu, mv, [&](int i, int j) { return rows[i][j]; });
      ps.patches.push_back(p);
    }
  // Corner (a, b) is the (0,0) corner of patch (a, b).
  for (int a = 0; a < patches_u; ++a)
    for (int b = 0; b < patches_v; ++b)
      ps.corners.push_back({ps.patches[patch_index(a, b)].pole(0, 0), -1});
  for (int a = 0; a < patches_u; ++a)
    for (int b = 0; b < patches_v; ++b)
      ps.patches[patch_index(a, b)].corners = {{patch_index(a, b), patch_index(a + 1, b),
                                                 patch_index(a + 1, b + 1), patch_index(a, b + 1)}};
  for (int a = 0; a < patches_u; ++a)
    for (int b = 0; b < patches_v; ++b) {
      // Curve along u at v = b: side 0 of patch (a, b), side 2 (backwards) of patch (a, b-1).
      const int h = add_curve_from_side(ps, patch_index(a, b), 0, Continuity::C2);
      attach(ps, patch_index(a, b - 1), 2, h, true);
      // Curve along v at u = a: side 1 of patch (a-1, b), side 3 (backwards) of patch (a, b).
      const int v = add_curve_from_side(ps, patch_index(a - 1, b), 1, Continuity::C2);
      attach(ps, patch_index(a, b), 3, v, true);
    }
  for (BoundaryCurve& c : ps.curves) c.continuity = Continuity::C2;
  ps.closed = true;
  ps.model_size = std::sqrt(2 * 8.0 * 8.0 + 2.0 * 2.0);  // bbox diagonal of the net, ~11.5
  return ps;
}

/// One open, gently curved patch over [0,2] x [0,1] with four boundary curves.
inline PatchSet open_patch() {
  PatchSet ps;
  NurbsPatch p = make_patch(1, 1, [](int i, int j) {
    return Point3{2 * i / 3.0, j / 3.0, 0.1 * (i == 1 || i == 2) * (j == 1 || j == 2)};
  });
  const int corner_pole[4][2] = {{0, 0}, {3, 0}, {3, 3}, {0, 3}};
  for (int c = 0; c < 4; ++c) {
    ps.corners.push_back({p.pole(corner_pole[c][0], corner_pole[c][1]), c});
    p.corners[c] = c;
  }
  ps.patches.push_back(p);
  for (int side = 0; side < 4; ++side) add_curve_from_side(ps, 0, side, Continuity::Boundary);
  ps.model_size = std::sqrt(5.0);
  return ps;
}

/// The triangle (0,0,0), (1,0,0), (1,1,0) as one patch x(u, v) = u (1, v, 0): side 3 (u = 0)
/// collapses to the apex, so it has no curve and corners 3 and 0 are the same corner.
inline PatchSet triangle_with_collapsed_side() {
  PatchSet ps;
  NurbsPatch p = make_patch(1, 1, [](int i, int j) {
    return Point3{i / 3.0, i / 3.0 * j / 3.0, 0};
  });
  ps.corners = {{{0, 0, 0}, 0}, {{1, 0, 0}, 1}, {{1, 1, 0}, 2}};
  p.corners = {{0, 1, 2, 0}};
  ps.patches.push_back(p);
  for (int side = 0; side < 3; ++side) add_curve_from_side(ps, 0, side, Continuity::Boundary);
  ps.model_size = std::sqrt(2.0);
  return ps;
}

}  // namespace subd2nurbs::testing
