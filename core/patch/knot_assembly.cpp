#include "core/patch/knot_assembly.h"

#include "core/nurbs/nurbs_eval.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

namespace subd2nurbs {

namespace {

void bernstein(double t, double b[4]) {
  const double s = 1 - t;
  b[0] = s * s * s;
  b[1] = 3 * t * s * s;
  b[2] = 3 * t * t * s;
  b[3] = t * t * t;
}

// Pieces are dyadic squares of size >= 2^-40; this offset picks the side of a boundary.
constexpr double kSide = 0x1p-46;

}  // namespace

LeafIndex::LeafIndex(const PatchLeaves& leaves) {
  nodes_.emplace_back();
  for (size_t i = 0; i < leaves.size(); ++i) {
    const PatchLeaf& l = leaves[i];
    int node = 0;
    double size = 1, x0 = 0, y0 = 0;
    while (size > l.size * 1.5) {
      size /= 2;
      const int cx = l.u0 >= x0 + size ? 1 : 0, cy = l.v0 >= y0 + size ? 1 : 0;
      x0 += cx * size;
      y0 += cy * size;
      if (nodes_[node].child[2 * cy + cx] < 0) {
        nodes_[node].child[2 * cy + cx] = static_cast<int>(nodes_.size());
        nodes_.emplace_back();
      }
      node = nodes_[node].child[2 * cy + cx];
    }
    nodes_[node].leaf = static_cast<int>(i);
  }
}

int LeafIndex::locate(double u, double v) const {
  u = std::clamp(u, 0.0, 1.0);
  v = std::clamp(v, 0.0, 1.0);
  int node = 0;
  double size = 1, x0 = 0, y0 = 0;
  for (;;) {
    const Node& n = nodes_[node];
    if (n.leaf >= 0) return n.leaf;
    size /= 2;
    const int cx = (u >= x0 + size && x0 + size < 1) ? 1 : 0, cy = (v >= y0 + size && y0 + size < 1) ? 1 : 0;
    x0 += cx * size;
    y0 += cy * size;
    node = n.child[2 * cy + cx];
    if (node < 0) throw std::logic_error("knot assembly: the pieces do not tile the patch");
  }
}

Point3 eval_leaf(const PatchLeaf& leaf, double u, double v, const Point3& origin) {
  double bu[4], bv[4];
  bernstein((u - leaf.u0) / leaf.size, bu);
  bernstein((v - leaf.v0) / leaf.size, bv);
  Point3 p{0, 0, 0};
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      const double w = bu[i] * bv[j];
      for (int d = 0; d < 3; ++d) p[d] += w * (leaf.net[i * 4 + j][d] - origin[d]);
    }
  return p;
}

namespace {

// Third derivative across the line (along u if across_u), times size^3 / 6, at parameter t of
// the other direction: the third difference of the Bezier rows, blended along the line.
Point3 third_difference(const PatchLeaf& leaf, bool across_u, double t) {
  double b[4];
  bernstein((t - (across_u ? leaf.v0 : leaf.u0)) / leaf.size, b);
  Point3 out{0, 0, 0};
  for (int k = 0; k < 4; ++k) {
    auto P = [&](int i) { return across_u ? leaf.net[i * 4 + k] : leaf.net[k * 4 + i]; };
    for (int d = 0; d < 3; ++d) out[d] += b[k] * (P(3)[d] - 3 * P(2)[d] + 3 * P(1)[d] - P(0)[d]);
  }
  return out;
}

}  // namespace

std::map<double, double> knot_line_jumps(const PatchLeaves& leaves, const LeafIndex& index, bool across_u) {
  std::map<double, double> jumps;
  static const double kFractions[4] = {0.1, 0.37, 0.63, 0.9};
  for (const PatchLeaf& la : leaves) {
    const double xi = (across_u ? la.u0 : la.v0) + la.size;  // the piece's far side
    if (xi >= 1) continue;
    const double t0 = across_u ? la.v0 : la.u0, t1 = t0 + la.size;
    double& worst = jumps[xi];
    for (double t = t0; t < t1;) {
      // The neighbour across the line at t, and the stretch both share.
      const int b = across_u ? index.locate(xi + kSide, t + kSide) : index.locate(t + kSide, xi + kSide);
      const PatchLeaf& lb = leaves[b];
      const double b0 = across_u ? lb.v0 : lb.u0;
      const double lo = std::max(t0, b0), hi = std::min(t1, b0 + lb.size);
      // Derivatives are 6 d / size^3; as a position at the smaller piece's scale h: d (h / size)^3.
      const double h = std::min(la.size, lb.size);
      const double sa = (h / la.size) * (h / la.size) * (h / la.size), sb = (h / lb.size) * (h / lb.size) * (h / lb.size);
      for (double f : kFractions) {
        const double tt = lo + f * (hi - lo);
        const Point3 da = third_difference(la, across_u, tt), db = third_difference(lb, across_u, tt);
        double n2 = 0;
        for (int d = 0; d < 3; ++d) n2 += (da[d] * sa - db[d] * sb) * (da[d] * sa - db[d] * sb);
        worst = std::max(worst, std::sqrt(n2));
      }
      t = hi;
    }
  }
  return jumps;
}

namespace {

// Interpolation at these parameters of a cell recovers its polynomial (4 x 4 samples).
const double kNodes[4] = {0.0380602337443566, 0.3086582838174551, 0.6913417161825449, 0.9619397662556434};

struct CellNet {
  Point3 b[16];
};

// Inverse of the 4x4 Bernstein collocation matrix at kNodes.
struct Collocation {
  double inv[4][4];
  Collocation() {
    double a[4][8];
    for (int r = 0; r < 4; ++r) {
      double b[4];
      bernstein(kNodes[r], b);
      for (int c = 0; c < 4; ++c) a[r][c] = b[c];
      for (int c = 0; c < 4; ++c) a[r][4 + c] = r == c ? 1 : 0;
    }
    for (int c = 0; c < 4; ++c) {
      int p = c;
      for (int r = c + 1; r < 4; ++r)
        if (std::abs(a[r][c]) > std::abs(a[p][c])) p = r;
      for (int k = 0; k < 8; ++k) std::swap(a[c][k], a[p][k]);
      const double d = a[c][c];
      for (int k = 0; k < 8; ++k) a[c][k] /= d;
      for (int r = 0; r < 4; ++r)
        if (r != c) {
          const double f = a[r][c];
          for (int k = 0; k < 8; ++k) a[r][k] -= f * a[c][k];
        }
    }
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) inv[r][c] = a[r][4 + c];
  }
};

// Blossom weights of the three arguments on the 4 Bezier points of [lo, hi].
void blossom_weights(const double* args, double lo, double hi, double w[4]);

// The cell's Bezier net relative to `origin` (a point of the patch: rounding then scales with
// the patch, not with the distance of the model from the coordinate origin).
CellNet cell_net(const PatchLeaves& leaves, const LeafIndex& index, double u0, double u1, double v0,
                 double v1, const Point3& origin) {
  // A cell inside one piece (the usual case: cells are no larger than the pieces near a fan) is
  // that piece restricted to the cell: Bezier point (i, j) of [a0, a1] x [b0, b1] in the piece's
  // own parameters is its blossom at (a0^(3-i) a1^i; b0^(3-j) b1^j).
  const PatchLeaf& leaf = leaves[index.locate((u0 + u1) / 2, (v0 + v1) / 2)];
  if (u0 >= leaf.u0 && u1 <= leaf.u0 + leaf.size && v0 >= leaf.v0 && v1 <= leaf.v0 + leaf.size) {
    double Ru[4][4], Rv[4][4];
    const double a[2] = {(u0 - leaf.u0) / leaf.size, (u1 - leaf.u0) / leaf.size};
    const double b[2] = {(v0 - leaf.v0) / leaf.size, (v1 - leaf.v0) / leaf.size};
    for (int i = 0; i < 4; ++i) {
      const double au[3] = {a[i > 2], a[i > 1], a[i > 0]}, bv[3] = {b[i > 2], b[i > 1], b[i > 0]};
      blossom_weights(au, 0, 1, Ru[i]);
      blossom_weights(bv, 0, 1, Rv[i]);
    }
    Point3 t[4][4];  // t[i][w] = sum_q Ru[i][q] (net[q][w] - origin)
    for (int i = 0; i < 4; ++i)
      for (int w = 0; w < 4; ++w) {
        t[i][w] = {0, 0, 0};
        for (int q = 0; q < 4; ++q)
          for (int d = 0; d < 3; ++d) t[i][w][d] += Ru[i][q] * (leaf.net[q * 4 + w][d] - origin[d]);
      }
    CellNet out;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) {
        Point3 p{0, 0, 0};
        for (int w = 0; w < 4; ++w)
          for (int d = 0; d < 3; ++d) p[d] += Rv[j][w] * t[i][w][d];
        out.b[i * 4 + j] = p;
      }
    return out;
  }
  // Otherwise the cell's polynomial from 4 x 4 values: b = C^-1 s C^-T.
  static const Collocation C;
  Point3 s[4][4];
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b) {
      const double u = u0 + kNodes[a] * (u1 - u0), v = v0 + kNodes[b] * (v1 - v0);
      s[a][b] = eval_leaf(leaves[index.locate(u, v)], u, v, origin);
    }
  Point3 t[4][4];
  for (int i = 0; i < 4; ++i)
    for (int b = 0; b < 4; ++b) {
      t[i][b] = {0, 0, 0};
      for (int a = 0; a < 4; ++a)
        for (int d = 0; d < 3; ++d) t[i][b][d] += C.inv[i][a] * s[a][b][d];
    }
  CellNet out;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      Point3 p{0, 0, 0};
      for (int b = 0; b < 4; ++b)
        for (int d = 0; d < 3; ++d) p[d] += C.inv[j][b] * t[i][b][d];
      out.b[i * 4 + j] = p;
    }
  return out;
}

// Blossom weights of the three arguments on the 4 Bezier points of [lo, hi].
void blossom_weights(const double* args, double lo, double hi, double w[4]) {
  w[0] = 1;
  w[1] = w[2] = w[3] = 0;
  int deg = 0;
  for (int k = 0; k < 3; ++k) {
    const double s = (args[k] - lo) / (hi - lo);
    for (int q = deg + 1; q >= 0; --q) w[q] = (q <= deg ? w[q] * (1 - s) : 0) + (q > 0 ? w[q - 1] * s : 0);
    ++deg;
  }
}

// For each pole of a clamped cubic with flat knots U: the span of its support whose
// polynomial is blossomed. Spans i+1 and i+2 lie between the pole's knots (the blossom
// interpolates there); the outer spans i and i+3 only when both inner ones are empty.
std::vector<int> pole_spans(const std::vector<double>& U) {
  const int np = static_cast<int>(U.size()) - 4;
  std::vector<int> spans(np);
  auto width = [&](int l) { return U[l + 1] - U[l]; };
  for (int i = 0; i < np; ++i) {
    int best = -1;
    for (int l : {i + 1, i + 2})
      if (width(l) > 0 && (best < 0 || width(l) > width(best))) best = l;
    if (best < 0)
      for (int l : {i, i + 3})
        if (width(l) > 0 && (best < 0 || width(l) > width(best))) best = l;
    spans[i] = best;
  }
  return spans;
}

KnotVector make_knots(const std::vector<double>& values, const std::vector<double>& doubles) {
  KnotVector kv;
  for (size_t i = 0; i < values.size(); ++i) {
    kv.knots.push_back(values[i]);
    int m = 1;
    if (i == 0 || i + 1 == values.size()) m = 4;
    else if (std::find(doubles.begin(), doubles.end(), values[i]) != doubles.end()) m = 2;
    kv.mults.push_back(m);
  }
  return kv;
}

}  // namespace

namespace {

// Knots (distinct values, ends included) -> poles by blossoming a cell of each pole's support.
void fill_poles(const PatchLeaves& leaves, const LeafIndex& index, const std::vector<double>& ku,
                const std::vector<double>& kv, const std::vector<double>& double_u, const std::vector<double>& double_v,
                NurbsPatch& patch) {
  patch.knots_u = make_knots(ku, double_u);
  patch.knots_v = make_knots(kv, double_v);
  const std::vector<double> U = patch.knots_u.flat(), V = patch.knots_v.flat();
  const std::vector<int> su = pole_spans(U), sv = pole_spans(V);
  patch.num_poles_u = static_cast<int>(su.size());
  patch.num_poles_v = static_cast<int>(sv.size());
  patch.poles.assign(static_cast<size_t>(patch.num_poles_u) * patch.num_poles_v, Point3{});
  std::map<std::pair<int, int>, CellNet> cells;
  const Point3 origin = leaves.front().net[0];
  for (int i = 0; i < patch.num_poles_u; ++i) {
    double wu[4];
    const int l = su[i];
    blossom_weights(&U[i + 1], U[l], U[l + 1], wu);
    for (int j = 0; j < patch.num_poles_v; ++j) {
      double wv[4];
      const int m = sv[j];
      blossom_weights(&V[j + 1], V[m], V[m + 1], wv);
      auto it = cells.find({l, m});
      if (it == cells.end()) it = cells.emplace(std::make_pair(l, m), cell_net(leaves, index, U[l], U[l + 1], V[m], V[m + 1], origin)).first;
      Point3 p{0, 0, 0};
      for (int q = 0; q < 4; ++q)
        for (int w = 0; w < 4; ++w)
          for (int d = 0; d < 3; ++d) p[d] += wu[q] * wv[w] * it->second.b[q * 4 + w][d];
      for (int d = 0; d < 3; ++d) p[d] += origin[d];
      patch.pole(i, j) = p;
    }
  }
}

// Largest distance between the patch and a piece at 4 x 4 parameters inside the piece: two
// bicubics that agree there are the same polynomial.
double leaf_error_with(const PatchLeaf& leaf, const PatchEvaluator& eval) {
  // The piece at the nodes: B net B^T with B the Bernstein values at the nodes.
  static const struct NodeBasis {
    double b[4][4];
    NodeBasis() {
      for (int a = 0; a < 4; ++a) bernstein(kNodes[a], b[a]);
    }
  } B;
  Point3 rows[4][4];  // rows[a][j] = sum_i B[a][i] net[i][j]
  for (int a = 0; a < 4; ++a)
    for (int j = 0; j < 4; ++j) {
      rows[a][j] = {0, 0, 0};
      for (int i = 0; i < 4; ++i)
        for (int d = 0; d < 3; ++d) rows[a][j][d] += B.b[a][i] * leaf.net[i * 4 + j][d];
    }
  double us[4], vs[4];
  for (int a = 0; a < 4; ++a) {
    us[a] = leaf.u0 + kNodes[a] * leaf.size;
    vs[a] = leaf.v0 + kNodes[a] * leaf.size;
  }
  Point3 p[16];
  eval.grid(us, 4, vs, 4, p);
  double worst = 0;
  for (int a = 0; a < 4; ++a)
    for (int c = 0; c < 4; ++c) {
      Point3 q{0, 0, 0};
      for (int j = 0; j < 4; ++j)
        for (int d = 0; d < 3; ++d) q[d] += B.b[c][j] * rows[a][j][d];
      const Point3& r = p[a * 4 + c];
      worst = std::max(worst, std::sqrt((r[0] - q[0]) * (r[0] - q[0]) + (r[1] - q[1]) * (r[1] - q[1]) + (r[2] - q[2]) * (r[2] - q[2])));
    }
  return worst;
}

}  // namespace

double leaf_error(const PatchLeaf& leaf, const NurbsPatch& patch) { return leaf_error_with(leaf, PatchEvaluator(patch)); }

AssemblyStats assemble_patch(const PatchLeaves& leaves, const std::vector<double>& double_u,
                             const std::vector<double>& double_v, double tolerance, double check,
                             NurbsPatch& patch) {
  AssemblyStats stats;
  if (leaves.size() == 1) {  // one bicubic: its Bezier net is the clamped single-span B-spline
    patch.knots_u = make_knots({0.0, 1.0}, {});
    patch.knots_v = patch.knots_u;
    patch.num_poles_u = patch.num_poles_v = 4;
    patch.poles.assign(leaves[0].net.begin(), leaves[0].net.end());
    return stats;
  }
  const LeafIndex index(leaves);
  std::vector<double> us{0.0, 1.0}, vs{0.0, 1.0};
  for (const PatchLeaf& l : leaves) {
    us.push_back(l.u0);
    us.push_back(l.u0 + l.size);
    vs.push_back(l.v0);
    vs.push_back(l.v0 + l.size);
  }
  for (auto* x : {&us, &vs}) {
    std::sort(x->begin(), x->end());
    x->erase(std::unique(x->begin(), x->end()), x->end());
  }
  // Remove simple knots across which the surface is one polynomial.
  std::map<double, double> jumps_u, jumps_v;
  auto reduce = [&](std::vector<double>& values, const std::vector<double>& doubles, bool across_u) {
    std::map<double, double>& jumps = across_u ? jumps_u : jumps_v;
    jumps = knot_line_jumps(leaves, index, across_u);
    std::vector<double> kept{values.front()};
    for (size_t i = 1; i + 1 < values.size(); ++i) {
      const double xi = values[i];
      const bool is_double = std::find(doubles.begin(), doubles.end(), xi) != doubles.end();
      const auto it = jumps.find(xi);
      if (!is_double && (it == jumps.end() || it->second <= tolerance)) continue;
      kept.push_back(xi);
    }
    kept.push_back(values.back());
    return kept;
  };
  std::vector<double> ru = reduce(us, double_u, true);
  std::vector<double> rv = reduce(vs, double_v, false);
  // The jump test is local: a knot whose pieces differ by a tiny c (u - xi)^3 at the pieces'
  // scale can still move the surface over the much longer span it is merged into. So the
  // result is checked against every piece, and where a piece is missed the removed knot of its
  // span with the largest jump is put back, until every piece is reproduced.
  for (int round = 0;; ++round) {
    fill_poles(leaves, index, ru, rv, double_u, double_v, patch);
    if (ru.size() == us.size() && rv.size() == vs.size()) break;  // nothing removed: exact by construction
    const PatchEvaluator eval(patch);
    // A piece needs checking only where its span lost knots in u or v.
    auto merged = [](const std::vector<double>& kept, const std::vector<double>& all, double mid) {
      const auto hi = std::upper_bound(kept.begin(), kept.end(), mid);
      const auto a = std::upper_bound(all.begin(), all.end(), *(hi - 1));
      return a != all.end() && *a < *hi;
    };
    std::vector<double> add_u, add_v;
    for (const PatchLeaf& l : leaves) {
      if (!merged(ru, us, l.u0 + l.size / 2) && !merged(rv, vs, l.v0 + l.size / 2)) continue;
      if (leaf_error_with(l, eval) <= check) continue;
      // The one removed knot, in u or v, of the piece's spans with the largest jump.
      double pick[2] = {-1, -1}, pick_jump[2] = {-1, -1};
      for (int dir = 0; dir < 2; ++dir) {
        const std::vector<double>& kept = dir == 0 ? ru : rv;
        const std::vector<double>& all = dir == 0 ? us : vs;
        const double mid = (dir == 0 ? l.u0 : l.v0) + l.size / 2;
        const auto hi = std::upper_bound(kept.begin(), kept.end(), mid);
        const double a = *(hi - 1), b = *hi;
        const std::map<double, double>& jumps = dir == 0 ? jumps_u : jumps_v;
        double best = -1, best_jump = -1;
        for (double x : all) {
          if (!(x > a && x < b)) continue;
          const auto it = jumps.find(x);
          const double j = it == jumps.end() ? 0.0 : it->second;
          if (j > best_jump) {
            best = x;
            best_jump = j;
          }
        }
        pick[dir] = best;
        pick_jump[dir] = best_jump;
      }
      const int dir = pick_jump[0] >= pick_jump[1] ? 0 : 1;
      if (pick[dir] >= 0) (dir == 0 ? add_u : add_v).push_back(pick[dir]);
    }
    if (add_u.empty() && add_v.empty()) break;
    if (round > 256) {  // give up: keep every knot
      ru = us;
      rv = vs;
      fill_poles(leaves, index, ru, rv, double_u, double_v, patch);
      break;
    }
    for (auto [kept, add] : {std::pair{&ru, &add_u}, std::pair{&rv, &add_v}}) {
      kept->insert(kept->end(), add->begin(), add->end());
      std::sort(kept->begin(), kept->end());
      kept->erase(std::unique(kept->begin(), kept->end()), kept->end());
    }
  }
  stats.removed_knots = static_cast<int>((us.size() - ru.size()) + (vs.size() - rv.size()));
  return stats;
}

}  // namespace subd2nurbs
