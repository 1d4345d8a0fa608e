#include "core/eval/self_intersection.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <optional>
#include <unordered_map>

#include "core/nurbs/nurbs_eval.h"
#include "core/util/parallel.h"

namespace subd2nurbs {

namespace {

constexpr double kPi = 3.14159265358979323846;

using Vec = Point3;

Vec sub(const Vec& a, const Vec& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec add(const Vec& a, const Vec& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
Vec scale(const Vec& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
double dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec cross(const Vec& a, const Vec& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double norm(const Vec& a) { return std::sqrt(dot(a, a)); }

struct Box {
  Vec lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  void add(const Vec& p) {
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], p[k]);
      hi[k] = std::max(hi[k], p[k]);
    }
  }
  void add(const Box& b) {
    add(b.lo);
    add(b.hi);
  }
  bool overlaps(const Box& b) const {
    for (int k = 0; k < 3; ++k)
      if (lo[k] > b.hi[k] || b.lo[k] > hi[k]) return false;
    return true;
  }
  bool contains(const Box& b, double eps) const {
    for (int k = 0; k < 3; ++k)
      if (b.lo[k] < lo[k] - eps || b.hi[k] > hi[k] + eps) return false;
    return true;
  }
};

/// A touched piece of a shared curve (curve >= 0, its parameter range) or a corner (curve < 0:
/// corner -curve - 2, range unused).
struct Tag {
  int curve;
  double s0, s1;
};

struct Tri {
  std::array<int, 3> v;  ///< welded vertex ids
  std::array<int, 3> g;  ///< the face's grid vertex indices (into Tess::uv)
  int face;
  int ci, cj;            ///< grid cell
  int tag_begin, tag_end;
};

struct Tess {
  std::vector<Vec> pos;                  ///< per grid vertex
  std::vector<std::array<double, 2>> uv; ///< per grid vertex
  std::vector<int> weld;                 ///< per grid vertex: welded id
  std::vector<Tri> tris;
  std::vector<Tag> tags;
  std::vector<Box> tri_box;
};

/// Grid lines of one direction of a patch: the knot lines of the direction, spans longer than
/// `h` split (at most max_split pieces), shorter ones merged (greedy on the length along the
/// direction, the largest over the other direction's knot lines); C0 knots always kept.
std::vector<double> grid_lines(const PatchEvaluator& ev, bool along_u, double h, int max_split, int grade_lo,
                               int grade_hi) {
  const NurbsPatch& p = ev.patch();
  const KnotVector& kd = along_u ? p.knots_u : p.knots_v;
  const KnotVector& ko = along_u ? p.knots_v : p.knots_u;
  constexpr int kSub = 4;
  std::vector<double> cand;
  for (size_t i = 0; i + 1 < kd.knots.size(); ++i)
    for (int k = 0; k < kSub; ++k) cand.push_back(kd.knots[i] + (kd.knots[i + 1] - kd.knots[i]) * k / kSub);
  cand.push_back(kd.knots.back());
  std::vector<double> probes(ko.knots.begin(), ko.knots.end());
  if (probes.size() == 2) probes.insert(probes.begin() + 1, 0.5 * (probes[0] + probes[1]));
  std::vector<Point3> pts(cand.size() * probes.size());
  if (along_u) {
    ev.grid(cand.data(), static_cast<int>(cand.size()), probes.data(), static_cast<int>(probes.size()), pts.data());
  } else {
    // out[a * nv + b] with a over u (probes), b over v (cand): transpose on reading.
    std::vector<Point3> t(pts.size());
    ev.grid(probes.data(), static_cast<int>(probes.size()), cand.data(), static_cast<int>(cand.size()), t.data());
    for (size_t a = 0; a < probes.size(); ++a)
      for (size_t b = 0; b < cand.size(); ++b) pts[b * probes.size() + a] = t[a * cand.size() + b];
  }
  const size_t np = probes.size();
  std::vector<double> out{kd.knots.front()};
  double acc = 0;
  for (size_t i = 0; i + 1 < kd.knots.size(); ++i) {
    double span = 0;
    for (int k = 0; k < kSub; ++k) {
      const size_t c = i * kSub + k;
      double longest = 0;
      for (size_t q = 0; q < np; ++q) longest = std::max(longest, norm(sub(pts[(c + 1) * np + q], pts[c * np + q])));
      span += longest;
    }
    const int pieces = std::clamp(static_cast<int>(std::ceil(span / h)), 1, max_split);
    const int m = std::max(kSub, pieces);
    const double a = kd.knots[i], b = kd.knots[i + 1];
    for (int k = 1; k <= m; ++k) {
      acc += span / m;
      const bool end = k == m;
      const bool c0 = end && i + 2 < kd.knots.size() && kd.mults[i + 1] >= 3;
      if (acc >= h * 0.999 || c0 || (end && i + 2 == kd.knots.size())) {
        out.push_back(end ? b : a + (b - a) * k / m);
        acc = 0;
      }
    }
  }
  // Graded towards an extraordinary corner: lines at 2^-k of the domain from that end.
  const double lo = kd.knots.front(), len = kd.knots.back() - lo;
  for (int k = 1; k <= grade_lo; ++k) out.push_back(lo + len * std::ldexp(1.0, -k));
  for (int k = 1; k <= grade_hi; ++k) out.push_back(lo + len * (1 - std::ldexp(1.0, -k)));
  std::sort(out.begin(), out.end());
  const double gap = 1e-3 * len * std::ldexp(1.0, -std::max(grade_lo, grade_hi));
  std::vector<double> unique;
  for (double x : out)
    if (unique.empty() || x - unique.back() > gap) unique.push_back(x);
  unique.back() = kd.knots.back();
  return unique;
}

/// The cell's touched boundary pieces: sides (as the curves' parameter ranges) and corners.
void cell_tags(const PatchSet& ps, const NurbsPatch& p, const std::vector<double>& us, const std::vector<double>& vs,
               int i, int j, std::vector<Tag>& tags) {
  const int nu = static_cast<int>(us.size()) - 1, nv = static_cast<int>(vs.size()) - 1;
  const double u0 = us.front(), u1 = us.back(), v0 = vs.front(), v1 = vs.back();
  const double ta = (us[i] - u0) / (u1 - u0), tb = (us[i + 1] - u0) / (u1 - u0);
  const double sa = (vs[j] - v0) / (v1 - v0), sb = (vs[j + 1] - v0) / (v1 - v0);
  auto side = [&](int s, double t0, double t1) {
    auto piece = [&](int curve, bool reversed, double p0, double p1) {
      if (curve < 0) return;
      const double lo = std::max(t0, p0), hi = std::min(t1, p1);
      if (lo > hi + 1e-12) return;
      double c0 = (lo - p0) / (p1 - p0), c1 = (hi - p0) / (p1 - p0);
      if (reversed) {
        c0 = 1 - c0;
        c1 = 1 - c1;
      }
      const double width = std::fabs(c1 - c0);
      tags.push_back({curve, std::min(c0, c1) - 0.5 * width - 1e-9, std::max(c0, c1) + 0.5 * width + 1e-9});
      const BoundaryCurve& bc = ps.curves[curve];
      if (c0 <= 1e-12 || c1 <= 1e-12) tags.push_back({-bc.corner0 - 2, 0, 0});
      if (c0 >= 1 - 1e-12 || c1 >= 1 - 1e-12) tags.push_back({-bc.corner1 - 2, 0, 0});
    };
    if (p.curves[s] >= 0) piece(p.curves[s], p.curve_reversed[s], 0, 1);
    for (const SidePiece& sp : p.split_sides[s]) piece(sp.curve, sp.reversed, sp.t0, sp.t1);
  };
  if (j == 0) side(0, ta, tb);
  if (i == nu - 1) side(1, sa, sb);
  if (j == nv - 1) side(2, 1 - tb, 1 - ta);
  if (i == 0) side(3, 1 - sb, 1 - sa);
  const bool at[4] = {i == 0 && j == 0, i == nu - 1 && j == 0, i == nu - 1 && j == nv - 1, i == 0 && j == nv - 1};
  for (int c = 0; c < 4; ++c)
    if (at[c] && p.corners[c] >= 0) tags.push_back({-p.corners[c] - 2, 0, 0});
}

bool tags_touch(const Tess& t, const Tri& a, const Tri& b) {
  for (int x = a.tag_begin; x < a.tag_end; ++x)
    for (int y = b.tag_begin; y < b.tag_end; ++y) {
      const Tag &p = t.tags[x], &q = t.tags[y];
      if (p.curve != q.curve) continue;
      if (p.curve < 0) return true;
      if (p.s0 <= q.s1 && q.s0 <= p.s1) return true;
    }
  return false;
}

/// Segment pq against triangle abc (not coplanar): the crossing point in x.
bool segment_triangle(const Vec& p, const Vec& q, const Vec& a, const Vec& b, const Vec& c, Vec& x) {
  const Vec n = cross(sub(b, a), sub(c, a));
  const double dp = dot(n, sub(p, a)), dq = dot(n, sub(q, a));
  if ((dp > 0 && dq > 0) || (dp < 0 && dq < 0) || dp == dq) return false;
  x = add(p, scale(sub(q, p), dp / (dp - dq)));
  if (dot(cross(sub(b, a), sub(x, a)), n) < 0) return false;
  if (dot(cross(sub(c, b), sub(x, b)), n) < 0) return false;
  if (dot(cross(sub(a, c), sub(x, c)), n) < 0) return false;
  return true;
}

/// True if no edge of P can cross triangle T: segment_triangle's first test (both ends strictly
/// on one side of T's plane, or at the same signed distance) holds for all three edges, computed
/// with the same expressions, so the answer is the one those three calls would give.
bool edges_miss_plane(const Vec* P, const Vec* T) {
  const Vec n = cross(sub(T[1], T[0]), sub(T[2], T[0]));
  const double d[3] = {dot(n, sub(P[0], T[0])), dot(n, sub(P[1], T[0])), dot(n, sub(P[2], T[0]))};
  for (int e = 0; e < 3; ++e) {
    const double dp = d[e], dq = d[(e + 1) % 3];
    if (!((dp > 0 && dq > 0) || (dp < 0 && dq < 0) || dp == dq)) return false;
  }
  return true;
}

bool triangles_cross(const Vec* A, const Vec* B, Vec& x) {
  // Most pairs whose boxes overlap lie on one side of each other's plane (or in one plane: the
  // slivers of a flat face of high valence): settled by two plane tests instead of six.
  if (edges_miss_plane(A, B) && edges_miss_plane(B, A)) return false;
  for (int e = 0; e < 3; ++e) {
    if (segment_triangle(A[e], A[(e + 1) % 3], B[0], B[1], B[2], x)) return true;
    if (segment_triangle(B[e], B[(e + 1) % 3], A[0], A[1], A[2], x)) return true;
  }
  return false;
}

/// Triangles A and B in one plane (B's vertices within `eps` of A's plane, the normals
/// parallel) that overlap with positive area: an edge of one properly crosses an edge of the
/// other, or a vertex lies strictly inside the other triangle. A point of the overlap in x.
/// (Sheets lying on each other, e.g. a flat cage folded over: no transversal crossing.)
bool triangles_overlap_in_plane(const Vec* A, const Vec* B, double eps, Vec& x) {
  const Vec n = cross(sub(A[1], A[0]), sub(A[2], A[0]));
  const double len = norm(n);
  if (len == 0) return false;
  const Vec u = scale(n, 1 / len);
  for (int k = 0; k < 3; ++k)
    if (std::fabs(dot(u, sub(B[k], A[0]))) > eps) return false;
  const Vec m = cross(sub(B[1], B[0]), sub(B[2], B[0]));
  if (norm(cross(n, m)) > 1e-6 * len * norm(m)) return false;
  // 2-D coordinates: drop the normal's largest component.
  int drop = 0;
  for (int k = 1; k < 3; ++k)
    if (std::fabs(n[k]) > std::fabs(n[drop])) drop = k;
  const int i0 = drop == 0 ? 1 : 0, i1 = drop == 2 ? 1 : 2;
  using P = std::array<double, 2>;
  P a[3], b[3];
  for (int k = 0; k < 3; ++k) {
    a[k] = {A[k][i0], A[k][i1]};
    b[k] = {B[k][i0], B[k][i1]};
  }
  const auto orient = [](const P& p, const P& q, const P& r) {
    return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]);
  };
  // Twice the larger triangle's area: what "strictly" is measured against.
  const double area = std::max(std::fabs(orient(a[0], a[1], a[2])), std::fabs(orient(b[0], b[1], b[2])));
  const double strict = 1e-9 * area;
  const auto strictly_inside = [&](const P* t, const P& q) {
    const double s = orient(t[0], t[1], t[2]) > 0 ? 1 : -1;
    return s * orient(t[0], t[1], q) > strict && s * orient(t[1], t[2], q) > strict && s * orient(t[2], t[0], q) > strict;
  };
  for (int k = 0; k < 3; ++k) {
    if (strictly_inside(a, b[k])) return x = B[k], true;
    if (strictly_inside(b, a[k])) return x = A[k], true;
  }
  for (int e = 0; e < 3; ++e)
    for (int f = 0; f < 3; ++f) {
      const P &p = a[e], &q = a[(e + 1) % 3], &r = b[f], &t = b[(f + 1) % 3];
      const double d1 = orient(p, q, r), d2 = orient(p, q, t), d3 = orient(r, t, p), d4 = orient(r, t, q);
      if (((d1 > strict && d2 < -strict) || (d1 < -strict && d2 > strict)) &&
          ((d3 > strict && d4 < -strict) || (d3 < -strict && d4 > strict))) {
        const double w = d3 / (d3 - d4);
        x = add(A[e], scale(sub(A[(e + 1) % 3], A[e]), w));
        return true;
      }
    }
  return false;
}

struct Node {
  Box box;
  int left = -1, right = -1;  ///< children, or -1 for a leaf
  int begin = 0, end = 0;     ///< the node's triangles: a range of `order`
  double box_volume() const {
    return (box.hi[0] - box.lo[0]) + (box.hi[1] - box.lo[1]) + (box.hi[2] - box.lo[2]);
  }
};

/// A node's hub (-1: none, or several) and the angular range of its triangles around it.
struct NodeArc {
  int hub = -1;
  float lo = 0, hi = 0;
};

struct Bvh {
  std::vector<Node> nodes;
  std::vector<int> order;
  std::vector<NodeArc> arcs;  ///< per node, when there are hubs
};

/// Hub ordering (SelfIntersectionOptions::hub_valence): per triangle the hub whose faces it
/// belongs to and its angular range [lo, hi] around it (-1: none; all three empty when there is
/// no hub); per hub the angular width below which a group of its triangles is split in space,
/// not by angle.
struct HubArcs {
  std::vector<int> hub;
  std::vector<float> lo, hi;  ///< rounded outwards: they hold the exact ranges
  std::vector<double> split_width;
};

/// Two angular ranges around one hub, [a0, a1] and [b0, b1] (a0, b0 in [0, 2 pi)), that are
/// apart on the circle.
bool arcs_apart(double a0, double a1, double b0, double b1) {
  constexpr double kGap = 1e-9;
  if ((a1 - a0) + (b1 - b0) >= 2 * kPi - 2 * kGap) return false;
  for (int k = -1; k <= 1; ++k)  // widths below 2 pi: no other shift can overlap
    if (b0 + 2 * k * kPi <= a1 + kGap && a0 <= b1 + 2 * k * kPi + kGap) return false;
  return true;
}

/// A bounding volume hierarchy over the triangles: median splits along the longest axis of the
/// boxes' centres, leaves of at most 4 triangles. With hubs, a node holding triangles of several
/// hubs (or of none) is first split between them, and a node of one hub's triangles is split by
/// angle around it while wider than the hub's split_width: such nodes are compared only when
/// their angular ranges meet. Without hubs the tree is the spatial one alone.
Bvh build_bvh(const Tess& t, const HubArcs& arcs) {
  Bvh bvh;
  const int n = static_cast<int>(t.tris.size());
  bvh.order.resize(n);
  std::vector<Vec> centre(n);
  for (int i = 0; i < n; ++i) {
    bvh.order[i] = i;
    centre[i] = scale(add(t.tri_box[i].lo, t.tri_box[i].hi), 0.5);
  }
  if (n == 0) return bvh;
  bvh.nodes.reserve(2 * n / 4 + 4);
  struct Item {
    int node, begin, end;
  };
  std::vector<Item> stack;
  bvh.nodes.emplace_back();
  stack.push_back({0, 0, n});
  if (!arcs.hub.empty()) bvh.arcs.reserve(bvh.nodes.capacity());
  auto middle = [&](int i) { return 0.5 * (double(arcs.lo[i]) + double(arcs.hi[i])); };
  auto hub_of = [&](int i) { return arcs.hub.empty() ? -1 : arcs.hub[i]; };
  while (!stack.empty()) {
    const Item it = stack.back();
    stack.pop_back();
    Box box, cbox;
    const int hub0 = hub_of(bvh.order[it.begin]);
    bool one_hub = true;
    float lo = 1e30f, hi = -1e30f;
    double mid_lo = 1e300, mid_hi = -1e300;
    for (int k = it.begin; k < it.end; ++k) {
      const int i = bvh.order[k];
      box.add(t.tri_box[i]);
      cbox.add(centre[i]);
      if (hub_of(i) != hub0) one_hub = false;
      if (hub_of(i) >= 0) {
        lo = std::min(lo, arcs.lo[i]);
        hi = std::max(hi, arcs.hi[i]);
        mid_lo = std::min(mid_lo, middle(i));
        mid_hi = std::max(mid_hi, middle(i));
      }
    }
    Node& node = bvh.nodes[it.node];
    node.box = box;
    node.begin = it.begin;
    node.end = it.end;
    if (!arcs.hub.empty()) {
      bvh.arcs.resize(bvh.nodes.size());
      if (one_hub && hub0 >= 0) bvh.arcs[it.node] = {hub0, lo, hi};
    }
    if (it.end - it.begin <= 4) continue;
    auto first = bvh.order.begin() + it.begin, last = bvh.order.begin() + it.end;
    int mid = (it.begin + it.end) / 2;
    if (!one_hub) {
      // Between hubs: grouped by hub (none first), cut at the group boundary nearest the middle.
      std::sort(first, last, [&](int a, int b) { return arcs.hub[a] != arcs.hub[b] ? arcs.hub[a] < arcs.hub[b] : a < b; });
      int best = -1;
      for (int k = it.begin + 1; k < it.end; ++k)
        if (arcs.hub[bvh.order[k]] != arcs.hub[bvh.order[k - 1]] &&
            (best < 0 || std::abs(k - mid) < std::abs(best - mid)))
          best = k;
      mid = best;
    } else if (hub0 >= 0 && mid_hi - mid_lo > arcs.split_width[hub0]) {
      std::nth_element(first, bvh.order.begin() + mid, last, [&](int a, int b) {
        return middle(a) != middle(b) ? middle(a) < middle(b) : a < b;
      });
    } else {
      int axis = 0;
      for (int k = 1; k < 3; ++k)
        if (cbox.hi[k] - cbox.lo[k] > cbox.hi[axis] - cbox.lo[axis]) axis = k;
      std::nth_element(first, bvh.order.begin() + mid, last,
                       [&](int a, int b) { return centre[a][axis] < centre[b][axis]; });
    }
    const int l = static_cast<int>(bvh.nodes.size());
    bvh.nodes.emplace_back();
    bvh.nodes.emplace_back();
    bvh.nodes[it.node].left = l;
    bvh.nodes[it.node].right = l + 1;
    stack.push_back({l, it.begin, mid});
    stack.push_back({l + 1, mid, it.end});
  }
  return bvh;
}

struct Candidate {
  int ta, tb;
  Vec x;
};

/// Barycentric parameters of x (projected) in triangle t: the (u, v) there.
std::array<double, 2> uv_at(const Tess& t, const Tri& tri, const Vec& x) {
  const Vec& a = t.pos[tri.g[0]];
  const Vec e1 = sub(t.pos[tri.g[1]], a), e2 = sub(t.pos[tri.g[2]], a), r = sub(x, a);
  const double a11 = dot(e1, e1), a12 = dot(e1, e2), a22 = dot(e2, e2), b1 = dot(e1, r), b2 = dot(e2, r);
  const double det = a11 * a22 - a12 * a12;
  double beta = 1.0 / 3, gamma = 1.0 / 3;
  if (det > 0) {
    beta = std::clamp((a22 * b1 - a12 * b2) / det, 0.0, 1.0);
    gamma = std::clamp((a11 * b2 - a12 * b1) / det, 0.0, 1.0 - beta);
  }
  std::array<double, 2> uv{};
  for (int k = 0; k < 2; ++k)
    uv[k] = (1 - beta - gamma) * t.uv[tri.g[0]][k] + beta * t.uv[tri.g[1]][k] + gamma * t.uv[tri.g[2]][k];
  return uv;
}

struct Domain {
  double u0, u1, v0, v1;
  bool on_boundary(double u, double v) const {
    const double eu = 1e-7 * (u1 - u0), ev = 1e-7 * (v1 - v0);
    return u <= u0 + eu || u >= u1 - eu || v <= v0 + ev || v >= v1 - ev;
  }
};

Domain domain(const NurbsPatch& p) {
  return {p.knots_u.knots.front(), p.knots_u.knots.back(), p.knots_v.knots.front(), p.knots_v.knots.back()};
}

/// Newton (minimum-norm steps) for S_a(ua, va) = S_b(ub, vb) from x0; true when it converges
/// to within `tol`.
bool solve_crossing(const PatchEvaluator& ea, const PatchEvaluator& eb, const Domain& da, const Domain& db,
                    double x0[4], double tol, SurfaceDerivs& sa, SurfaceDerivs& sb) {
  double* x = x0;
  const double lo[4] = {da.u0, da.v0, db.u0, db.v0}, hi[4] = {da.u1, da.v1, db.u1, db.v1};
  for (int it = 0; it < 40; ++it) {
    sa = ea.derivs(x[0], x[1], 1);
    sb = eb.derivs(x[2], x[3], 1);
    const Vec F = sub(sa.p, sb.p);
    if (norm(F) <= tol) return true;
    const Vec c[4] = {sa.du, sa.dv, scale(sb.du, -1), scale(sb.dv, -1)};
    double A[3][3] = {};
    for (const Vec& ck : c)
      for (int r = 0; r < 3; ++r)
        for (int s = 0; s < 3; ++s) A[r][s] += ck[r] * ck[s];
    const auto determinant = [&] {
      return A[0][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1]) - A[0][1] * (A[1][0] * A[2][2] - A[1][2] * A[2][0]) +
             A[0][2] * (A[1][0] * A[2][1] - A[1][1] * A[2][0]);
    };
    double det = determinant();
    const double scale_a = A[0][0] + A[1][1] + A[2][2];
    if (!(std::fabs(det) > 1e-14 * scale_a * scale_a * scale_a)) {
      // Tangent planes: every derivative in one plane. Steps within it (A + |A| n n^T): sheets
      // lying on each other converge, parallel sheets apart do not.
      const Vec n = cross(sa.du, sa.dv);
      const double nn = dot(n, n);
      if (!(nn > 0)) return false;
      for (int r = 0; r < 3; ++r)
        for (int s = 0; s < 3; ++s) A[r][s] += scale_a * n[r] * n[s] / nn;
      det = determinant();
      if (!(std::fabs(det) > 1e-14 * scale_a * scale_a * scale_a)) return false;
    }
    // y = A^-1 F by Cramer's rule.
    Vec y;
    for (int k = 0; k < 3; ++k) {
      double M[3][3];
      for (int r = 0; r < 3; ++r)
        for (int s = 0; s < 3; ++s) M[r][s] = s == k ? F[r] : A[r][s];
      y[k] = (M[0][0] * (M[1][1] * M[2][2] - M[1][2] * M[2][1]) - M[0][1] * (M[1][0] * M[2][2] - M[1][2] * M[2][0]) +
              M[0][2] * (M[1][0] * M[2][1] - M[1][1] * M[2][0])) /
             det;
    }
    for (int k = 0; k < 4; ++k) {
      double d = -dot(c[k], y);
      const double limit = 0.25 * (hi[k] - lo[k]);
      d = std::clamp(d, -limit, limit);
      x[k] = std::clamp(x[k] + d, lo[k], hi[k]);
    }
  }
  return false;
}

uint64_t pair_key(int a, int b) { return (static_cast<uint64_t>(a) << 32) | static_cast<uint32_t>(b); }

/// Ray parity: is x inside the closed triangle set `tris` (indices into t.tris)?
bool inside(const Tess& t, const std::vector<int>& tris, const Vec& x) {
  const Vec d{0.5377321, 0.6143298, 0.5774401};
  int crossings = 0;
  for (int i : tris) {
    const Tri& tri = t.tris[i];
    const Vec &a = t.pos[tri.g[0]], &b = t.pos[tri.g[1]], &c = t.pos[tri.g[2]];
    const Vec e1 = sub(b, a), e2 = sub(c, a), pv = cross(d, e2);
    const double det = dot(e1, pv);
    if (det == 0) continue;
    const Vec tv = sub(x, a);
    const double u = dot(tv, pv) / det;
    if (u < 0 || u > 1) continue;
    const Vec qv = cross(tv, e1);
    const double v = dot(d, qv) / det;
    if (v < 0 || u + v > 1) continue;
    if (dot(e2, qv) / det > 0) ++crossings;
  }
  return crossings % 2 == 1;
}

}  // namespace

SelfIntersectionReport find_self_intersections(const PatchSet& ps, const SelfIntersectionOptions& options) {
  SelfIntersectionReport r;
  const int nf = static_cast<int>(ps.patches.size());
  const double size = ps.model_size > 0 ? ps.model_size : 1.0;
  // Components by shared curves.
  std::vector<int> parent(nf);
  for (int f = 0; f < nf; ++f) parent[f] = f;
  auto find = [&](int f) {
    while (parent[f] != f) f = parent[f] = parent[parent[f]];
    return f;
  };
  for (const BoundaryCurve& c : ps.curves)
    for (size_t k = 1; k < c.uses.size(); ++k) parent[find(c.uses[k].patch)] = find(c.uses[0].patch);
  r.component.assign(nf, -1);
  std::vector<int> id_of_root(nf, -1);
  for (int f = 0; f < nf; ++f) {
    const int root = find(f);
    if (id_of_root[root] < 0) id_of_root[root] = r.components++;
    r.component[f] = id_of_root[root];
  }
  std::vector<char> closed(r.components, 1);
  for (const BoundaryCurve& c : ps.curves)
    if (c.uses.size() == 1) closed[r.component[c.uses[0].patch]] = 0;

  // Tessellation, one face per item, then concatenated.
  const double h = options.step * size;
  std::vector<PatchEvaluator> evals;
  evals.reserve(nf);
  for (const NurbsPatch& p : ps.patches) evals.emplace_back(p);
  struct FaceTess {
    std::vector<double> us, vs;
    std::vector<Point3> pts;
    std::vector<Tag> tags;
    std::vector<std::array<int, 2>> tag_range;  ///< per cell
  };
  std::vector<FaceTess> ft(nf);
  std::vector<int> corner_faces(ps.corners.size(), 0);
  for (const NurbsPatch& p : ps.patches)
    for (int c : p.corners)
      if (c >= 0) ++corner_faces[c];
  parallel_for(nf, [&](int f) {
    FaceTess& t = ft[f];
    // Faces at an extraordinary vertex (a corner not shared by 4 faces) fold most tightly
    // near it (catmark_rook's crenellations cross within 1e-4 of the model size of one): the
    // grid is graded towards such corners.
    const NurbsPatch& p = ps.patches[f];
    bool ev[4] = {false, false, false, false};
    // Not at high valences: there the graded cells of every face crowd into one tiny ball and
    // the pairs to sort out grow with the square of the valence (catmark_pole360: 60 s).
    if (p.kind == PatchKind::Pccm)
      for (int c = 0; c < 4; ++c)
        ev[c] = p.corners[c] >= 0 && corner_faces[p.corners[c]] != 4 &&
                corner_faces[p.corners[c]] <= options.max_graded_valence;
    // Graded down to cells of about kFinest x the model size, not below.
    constexpr double kFinest = 1e-4;
    Box poles;
    for (const Point3& q : p.poles) poles.add(q);
    const double extent = norm(sub(poles.hi, poles.lo));
    const int g = std::clamp(static_cast<int>(std::floor(std::log2(std::max(1.0, extent / (kFinest * size))))), 0,
                             options.corner_grading);
    t.us = grid_lines(evals[f], true, h, options.max_split, ev[0] || ev[3] ? g : 0, ev[1] || ev[2] ? g : 0);
    t.vs = grid_lines(evals[f], false, h, options.max_split, ev[0] || ev[1] ? g : 0, ev[2] || ev[3] ? g : 0);
    t.pts.resize(t.us.size() * t.vs.size());
    evals[f].grid(t.us.data(), static_cast<int>(t.us.size()), t.vs.data(), static_cast<int>(t.vs.size()), t.pts.data());
    const int nu = static_cast<int>(t.us.size()) - 1, nv = static_cast<int>(t.vs.size()) - 1;
    t.tag_range.resize(static_cast<size_t>(nu) * nv);
    for (int i = 0; i < nu; ++i)
      for (int j = 0; j < nv; ++j) {
        const int b = static_cast<int>(t.tags.size());
        if (i == 0 || j == 0 || i == nu - 1 || j == nv - 1) cell_tags(ps, ps.patches[f], t.us, t.vs, i, j, t.tags);
        t.tag_range[static_cast<size_t>(i) * nv + j] = {b, static_cast<int>(t.tags.size())};
      }
  });
  Tess t;
  std::vector<int> face_vertex_base(nf);
  std::vector<std::array<int, 4>> face_corner_vertex(nf);  ///< the grid vertex at each corner of the domain
  for (int f = 0; f < nf; ++f) {
    const FaceTess& a = ft[f];
    const int base = static_cast<int>(t.pos.size());
    face_vertex_base[f] = base;
    const int nu = static_cast<int>(a.us.size()), nv = static_cast<int>(a.vs.size());
    face_corner_vertex[f] = {base, base + (nu - 1) * nv, base + (nu - 1) * nv + nv - 1, base + nv - 1};
    for (int i = 0; i < nu; ++i)
      for (int j = 0; j < nv; ++j) {
        t.pos.push_back(a.pts[static_cast<size_t>(i) * nv + j]);
        t.uv.push_back({a.us[i], a.vs[j]});
      }
    const int tag_base = static_cast<int>(t.tags.size());
    t.tags.insert(t.tags.end(), a.tags.begin(), a.tags.end());
    const double min_area2 = 1e-24 * size * size * size * size;
    for (int i = 0; i + 1 < nu; ++i)
      for (int j = 0; j + 1 < nv; ++j) {
        const int g00 = base + i * nv + j, g10 = base + (i + 1) * nv + j, g11 = g10 + 1, g01 = g00 + 1;
        const auto range = a.tag_range[static_cast<size_t>(i) * (nv - 1) + j];
        for (const std::array<int, 3>& g : {std::array<int, 3>{g00, g10, g11}, std::array<int, 3>{g00, g11, g01}}) {
          const Vec n = cross(sub(t.pos[g[1]], t.pos[g[0]]), sub(t.pos[g[2]], t.pos[g[0]]));
          if (dot(n, n) <= min_area2) continue;  // degenerate (a polar cap's pole)
          Tri tri{g, g, f, i, j, tag_base + range[0], tag_base + range[1]};
          t.tris.push_back(tri);
        }
      }
  }
  ft.clear();
  // Welded vertex ids: positions equal to 1e-9 of the model size (seams, poles, shared sides).
  {
    const double q = 1e-9 * size;
    std::unordered_map<uint64_t, int> cell;
    cell.reserve(t.pos.size());
    t.weld.resize(t.pos.size());
    for (size_t i = 0; i < t.pos.size(); ++i) {
      uint64_t key = 1469598103934665603ull;
      for (int k = 0; k < 3; ++k)
        key = (key ^ static_cast<uint64_t>(static_cast<int64_t>(std::llround(t.pos[i][k] / q)))) * 1099511628211ull;
      auto [it, fresh] = cell.emplace(key, static_cast<int>(i));
      t.weld[i] = it->second;
      (void)fresh;
    }
    for (Tri& tri : t.tris)
      for (int k = 0; k < 3; ++k) tri.v[k] = t.weld[tri.g[k]];
  }
  r.triangles = static_cast<long long>(t.tris.size());
  t.tri_box.resize(t.tris.size());
  const double pad = 1e-9 * size;
  for (size_t i = 0; i < t.tris.size(); ++i) {
    Box b;
    for (int k = 0; k < 3; ++k) b.add(t.pos[t.tris[i].g[k]]);
    for (int k = 0; k < 3; ++k) {
      b.lo[k] -= pad;
      b.hi[k] += pad;
    }
    t.tri_box[i] = b;
  }
  // Hubs (SelfIntersectionOptions::hub_valence): a corner of more faces than that, its normal
  // the sum of the unit normals of the triangles there. A triangle of a face at a hub gets its
  // angular range around the hub, seen along that normal, when its projection misses the hub
  // (its vertices, other than one at the hub, within a half-turn): two triangles whose ranges are
  // apart have projections that are apart and cannot meet. A vertex welded to the hub counts as
  // at it, so such ranges are exact up to the weld (1e-9 of the model size), where two faces at
  // the hub touch anyway.
  HubArcs arcs;  // empty without hubs
  if (options.hub_valence > 0) {
    struct Hub {
      Vec p{}, n{0, 0, 0}, e1{}, e2{};
    };
    std::vector<Hub> hubs;
    std::vector<int> hub_of(ps.corners.size(), -1), face_hub(nf, -1);
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < 4 && face_hub[f] < 0; ++k) {
        const int c = ps.patches[f].corners[k];
        if (c < 0 || corner_faces[c] <= options.hub_valence) continue;
        if (hub_of[c] < 0) {
          hub_of[c] = static_cast<int>(hubs.size());
          Hub hub;
          hub.p = t.pos[face_corner_vertex[f][k]];
          hubs.push_back(hub);
          arcs.split_width.push_back(4 * kPi / corner_faces[c]);  // two faces' share of the turn
        }
        face_hub[f] = hub_of[c];
      }
    const double at_hub = 1e-9 * size;
    for (const Tri& tri : t.tris) {
      const int hb = face_hub[tri.face];
      if (hb < 0) continue;
      bool touches = false;
      for (int k = 0; k < 3; ++k) touches = touches || norm(sub(t.pos[tri.g[k]], hubs[hb].p)) <= at_hub;
      if (!touches) continue;
      const Vec n = cross(sub(t.pos[tri.g[1]], t.pos[tri.g[0]]), sub(t.pos[tri.g[2]], t.pos[tri.g[0]]));
      if (const double l = norm(n); l > 0) hubs[hb].n = add(hubs[hb].n, scale(n, 1 / l));
    }
    for (Hub& hub : hubs) {
      const double l = norm(hub.n);
      if (!(l > 0)) {  // no usable normal: its triangles stay unordered
        hub.n = {0, 0, 0};
        continue;
      }
      hub.n = scale(hub.n, 1 / l);
      const int k = std::abs(hub.n[0]) < 0.6 ? 0 : std::abs(hub.n[1]) < 0.6 ? 1 : 2;
      Vec axis{0, 0, 0};
      axis[k] = 1;
      hub.e1 = cross(hub.n, axis);
      hub.e1 = scale(hub.e1, 1 / norm(hub.e1));
      hub.e2 = cross(hub.n, hub.e1);
    }
    if (!hubs.empty()) {
      arcs.hub.assign(t.tris.size(), -1);
      arcs.lo.assign(t.tris.size(), 0.0f);
      arcs.hi.assign(t.tris.size(), 0.0f);
    }
    for (size_t i = 0; i < arcs.hub.size(); ++i) {
      const Tri& tri = t.tris[i];
      const int hb = face_hub[tri.face];
      if (hb < 0 || norm(hubs[hb].n) == 0) continue;
      double angle[3];
      int m = 0;
      bool ok = true;
      for (int k = 0; k < 3 && ok; ++k) {
        const Vec d = sub(t.pos[tri.g[k]], hubs[hb].p);
        const double x = dot(d, hubs[hb].e1), y = dot(d, hubs[hb].e2), l = norm(d);
        if (l <= at_hub) continue;
        if (std::hypot(x, y) <= 1e-6 * l) ok = false;  // straight above or below the hub: no angle
        angle[m++] = std::atan2(y, x);
      }
      if (!ok || m < 2) continue;
      double dmin = 0, dmax = 0;
      for (int k = 1; k < m; ++k) {
        const double d = std::remainder(angle[k] - angle[0], 2 * kPi);
        dmin = std::min(dmin, d);
        dmax = std::max(dmax, d);
      }
      if (dmax - dmin >= kPi - 1e-6) continue;  // a half-turn or more: its projection may hold the hub
      double lo = angle[0] + dmin;
      lo -= 2 * kPi * std::floor(lo / (2 * kPi));
      arcs.hub[i] = hb;
      arcs.lo[i] = std::nextafter(static_cast<float>(lo), -1.0f);
      arcs.hi[i] = std::nextafter(static_cast<float>(lo + (dmax - dmin)), 10.0f);
    }
    r.hubs = static_cast<int>(hubs.size());
  }
  const Bvh bvh = build_bvh(t, arcs);
  // Triangles this close to one plane are tested for lying on each other (the tessellations of
  // two flat sheets in one plane agree to rounding).
  const double coplanar = 1e-9 * size;

  // Candidate triangle pairs, up to candidates_per_pair per pair of faces: the first ones in
  // the order of a depth-first walk over the pairs of BVH nodes whose boxes overlap.
  struct Found {
    long long crossings = 0, tested = 0;
    std::map<uint64_t, std::vector<Candidate>> lists;
  };
  auto test_pair = [&](int ia, int ib, Found& out) {
    if (!t.tri_box[ia].overlaps(t.tri_box[ib])) return;
    if (!arcs.hub.empty() && arcs.hub[ia] >= 0 && arcs.hub[ia] == arcs.hub[ib] &&
        arcs_apart(arcs.lo[ia], arcs.hi[ia], arcs.lo[ib], arcs.hi[ib]))
      return;
    ++out.tested;
    const Tri* a = &t.tris[ia];
    const Tri* b = &t.tris[ib];
    if (a->face > b->face) std::swap(a, b), std::swap(ia, ib);
    for (int x = 0; x < 3; ++x)
      for (int y = 0; y < 3; ++y)
        if (a->v[x] == b->v[y]) return;
    if (a->face == b->face && std::abs(a->ci - b->ci) <= 1 && std::abs(a->cj - b->cj) <= 1) return;
    if (tags_touch(t, *a, *b)) return;
    const Vec A[3] = {t.pos[a->g[0]], t.pos[a->g[1]], t.pos[a->g[2]]};
    const Vec B[3] = {t.pos[b->g[0]], t.pos[b->g[1]], t.pos[b->g[2]]};
    Vec x;
    if (!triangles_cross(A, B, x) && !triangles_overlap_in_plane(A, B, coplanar, x)) return;
    ++out.crossings;
    std::vector<Candidate>& list = out.lists[pair_key(a->face, b->face)];
    if (static_cast<int>(list.size()) < options.candidates_per_pair) list.push_back({ia, ib, x});
  };
  // One step of the walk: a pair of nodes (n == m: the pairs within one node). Leaves test
  // their triangles; otherwise the children's pairs are pushed (visited last pushed first).
  using NodePair = std::pair<int, int>;
  auto step = [&](const NodePair& item, std::vector<NodePair>& stack, Found& out) {
    const auto [n, m] = item;
    const Node &N = bvh.nodes[n], &M = bvh.nodes[m];
    if (n == m) {
      if (N.left < 0) {
        for (int x = N.begin; x < N.end; ++x)
          for (int y = x + 1; y < N.end; ++y) test_pair(bvh.order[x], bvh.order[y], out);
      } else {
        stack.push_back({N.left, N.left});
        stack.push_back({N.right, N.right});
        stack.push_back({N.left, N.right});
      }
      return;
    }
    if (!N.box.overlaps(M.box)) return;
    if (!bvh.arcs.empty()) {
      const NodeArc &a = bvh.arcs[n], &b = bvh.arcs[m];
      if (a.hub >= 0 && a.hub == b.hub && arcs_apart(a.lo, a.hi, b.lo, b.hi)) return;
    }
    if (N.left < 0 && M.left < 0) {
      for (int x = N.begin; x < N.end; ++x)
        for (int y = M.begin; y < M.end; ++y) test_pair(bvh.order[x], bvh.order[y], out);
    } else if (M.left < 0 || (N.left >= 0 && N.box_volume() >= M.box_volume())) {
      stack.push_back({N.left, m});
      stack.push_back({N.right, m});
    } else {
      stack.push_back({n, M.left});
      stack.push_back({n, M.right});
    }
  };
  // The walk is cut into tasks: node pairs of at most kTaskTriangles triangles between them, in
  // the order the walk reaches them. Each task walks its own part; taking the tasks' lists in
  // that order gives the same first candidates as one walk (a high-valence vertex's thin faces
  // gave millions of triangle pairs: catmark capsule of valence 1024, 40 % of its conversion,
  // before the hubs' angular order; a bipyramid of valence 256 now tests 10 M pairs, 50 M before).
  constexpr int kTaskTriangles = 4096;
  std::vector<NodePair> tasks;
  if (!bvh.nodes.empty()) {
    std::vector<NodePair> stack{{0, 0}};
    while (!stack.empty()) {
      const NodePair item = stack.back();
      stack.pop_back();
      const Node &N = bvh.nodes[item.first], &M = bvh.nodes[item.second];
      const int triangles = (N.end - N.begin) + (item.first == item.second ? 0 : M.end - M.begin);
      if (triangles <= kTaskTriangles) {
        tasks.push_back(item);
        continue;
      }
      Found none;  // a step above the tasks' size pushes children and tests nothing (no leaf is that large)
      step(item, stack, none);
    }
  }
  std::vector<Found> task_found(tasks.size());
  parallel_for(static_cast<int>(tasks.size()), [&](int k) {
    std::vector<NodePair> stack{tasks[static_cast<size_t>(k)]};
    while (!stack.empty()) {
      const NodePair item = stack.back();
      stack.pop_back();
      step(item, stack, task_found[static_cast<size_t>(k)]);
    }
  });
  std::map<uint64_t, std::vector<Candidate>> candidates;
  for (Found& f : task_found) {
    r.candidate_pairs += f.crossings;
    r.tested_pairs += f.tested;
    for (auto& [key, list] : f.lists) {
      std::vector<Candidate>& all = candidates[key];
      for (const Candidate& c : list)
        if (static_cast<int>(all.size()) < options.candidates_per_pair) all.push_back(c);
    }
  }
  task_found.clear();

  // Neighbours: faces sharing a curve or a corner (their crossing on the shared boundary is
  // the trivial one).
  std::vector<std::vector<int>> face_touch(nf);  ///< curve ids and -corner - 2
  for (int f = 0; f < nf; ++f) {
    const NurbsPatch& p = ps.patches[f];
    for (int s = 0; s < 4; ++s) {
      if (p.corners[s] >= 0) face_touch[f].push_back(-p.corners[s] - 2);
      auto curve = [&](int c) {
        if (c < 0) return;
        face_touch[f].push_back(c);
        face_touch[f].push_back(-ps.curves[c].corner0 - 2);
        face_touch[f].push_back(-ps.curves[c].corner1 - 2);
      };
      curve(p.curves[s]);
      for (const SidePiece& sp : p.split_sides[s]) curve(sp.curve);
    }
    std::sort(face_touch[f].begin(), face_touch[f].end());
  }
  auto neighbours = [&](int a, int b) {
    if (a == b) return true;
    const std::vector<int>&x = face_touch[a], &y = face_touch[b];
    size_t i = 0, j = 0;
    while (i < x.size() && j < y.size()) {
      if (x[i] == y[j]) return true;
      if (x[i] < y[j]) ++i;
      else ++j;
    }
    return false;
  };

  // Confirmation on the exact surfaces, one face pair per item.
  std::vector<std::pair<uint64_t, const std::vector<Candidate>*>> pairs;
  for (const auto& [key, list] : candidates) pairs.push_back({key, &list});
  std::vector<FaceCrossing> found(pairs.size());
  std::vector<char> ok(pairs.size(), 0);
  const double tol = 1e-10 * size;
  parallel_for(static_cast<int>(pairs.size()), [&](int k) {
    const int fa = static_cast<int>(pairs[k].first >> 32), fb = static_cast<int>(pairs[k].first & 0xffffffffu);
    const Domain da = domain(ps.patches[fa]), db = domain(ps.patches[fb]);
    const bool near = neighbours(fa, fb);
    // A transversal crossing wins; else the first tangent solution away from the shared
    // boundary: the sheets touch or lie on each other there.
    std::optional<FaceCrossing> touch;
    for (const Candidate& c : *pairs[k].second) {
      const auto pa = uv_at(t, t.tris[c.ta], c.x), pb = uv_at(t, t.tris[c.tb], c.x);
      double x[4] = {pa[0], pa[1], pb[0], pb[1]};
      SurfaceDerivs sa, sb;
      if (!solve_crossing(evals[fa], evals[fb], da, db, x, tol, sa, sb)) continue;
      const Vec na = unit_normal(sa), nb = unit_normal(sb);
      if (dot(na, na) == 0 || dot(nb, nb) == 0) continue;  // singular
      if (near && da.on_boundary(x[0], x[1]) && db.on_boundary(x[2], x[3])) continue;  // the shared boundary
      if (fa == fb && std::fabs(x[0] - x[2]) <= 1e-7 * (da.u1 - da.u0) && std::fabs(x[1] - x[3]) <= 1e-7 * (da.v1 - da.v0))
        continue;  // a face with itself: the trivial solution
      const double sine = norm(cross(na, nb));
      FaceCrossing w;
      w.face_a = fa;
      w.face_b = fb;
      w.component_a = r.component[fa];
      w.component_b = r.component[fb];
      w.ua = x[0];
      w.va = x[1];
      w.ub = x[2];
      w.vb = x[3];
      w.point = sa.p;
      w.angle_deg = std::asin(std::min(1.0, sine)) * 180 / 3.14159265358979323846;
      if (dot(na, nb) < 0) w.angle_deg = 180 - w.angle_deg;
      // Tangent, or on the edge of one face (a face standing on another, e.g. two boxes side by
      // side): the surfaces touch there without passing through each other.
      if (sine < 1e-3 || da.on_boundary(x[0], x[1]) || db.on_boundary(x[2], x[3])) {
        w.touching = true;
        if (!touch) touch = w;
        continue;
      }
      found[k] = w;
      ok[k] = 1;
      break;
    }
    if (!ok[k] && touch) {
      found[k] = *touch;
      ok[k] = 1;
    }
  });
  std::map<std::pair<int, int>, int> component_pairs;
  for (size_t k = 0; k < pairs.size(); ++k) {
    if (!ok[k]) continue;
    const FaceCrossing& w = found[k];
    if (w.component_a == w.component_b) {
      r.self.push_back(w);
    } else {
      r.overlaps.push_back(w);
      component_pairs[{std::min(w.component_a, w.component_b), std::max(w.component_a, w.component_b)}] = 1;
    }
  }

  // A closed component inside another closed one, without crossing it.
  if (r.components > 1) {
    std::vector<Box> cbox(r.components);
    std::vector<std::vector<int>> ctris(r.components);
    for (size_t i = 0; i < t.tris.size(); ++i) {
      const int c = r.component[t.tris[i].face];
      cbox[c].add(t.tri_box[i]);
      ctris[c].push_back(static_cast<int>(i));
    }
    for (int a = 0; a < r.components; ++a) {
      if (!closed[a] || ctris[a].empty()) continue;
      for (int b = 0; b < r.components; ++b) {
        if (a == b || !closed[b] || ctris[b].empty()) continue;
        if (component_pairs.count({std::min(a, b), std::max(a, b)})) continue;
        if (!cbox[b].contains(cbox[a], 0)) continue;
        const Tri& probe = t.tris[ctris[a].front()];
        const Vec x = t.pos[probe.g[0]];
        if (!inside(t, ctris[b], x)) continue;
        FaceCrossing w;
        w.face_a = probe.face;
        w.face_b = t.tris[ctris[b].front()].face;
        w.component_a = a;
        w.component_b = b;
        w.ua = t.uv[probe.g[0]][0];
        w.va = t.uv[probe.g[0]][1];
        w.point = x;
        w.inside = true;
        r.overlaps.push_back(w);
        component_pairs[{std::min(a, b), std::max(a, b)}] = 1;
      }
    }
  }
  for (const auto& [key, unused] : component_pairs) r.overlapping_components.push_back(key);
  return r;
}

}  // namespace subd2nurbs
