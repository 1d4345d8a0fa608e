#include "core/patch/packing.h"

#include <algorithm>
#include <array>
#include <climits>
#include <map>
#include <cmath>
#include <queue>
#include <utility>

#include "core/patch/patch_builder.h"
#include "core/util/tolerances.h"

namespace subd2nurbs {

void place_parameters(const PatchPlace& place, double s, double t, double& u, double& v) {
  double x, y;  // in the cell, from its (u, v) corner
  switch (place.rotation & 3) {
    case 0: x = s; y = t; break;
    case 1: x = t; y = 1 - s; break;
    case 2: x = 1 - s; y = 1 - t; break;
    default: x = 1 - t; y = s; break;
  }
  u = place.u + x;
  v = place.v + y;
}

namespace {

// A grid state is a packable patch seen with a rotation: 4 * patch + rotation. With rotation r
// the cell's side l is the quad's side (l + r) mod 4, so the cell's +u neighbour is across the
// quad's side r + 1 and its +v neighbour across side r + 2.
struct Grid {
  std::vector<std::array<std::pair<int, int>, 4>> neighbour;  ///< per patch and side: (patch, side) or (-1, -1)

  /// The state one cell further along u (dir 0) or v (dir 1), -1 if the way is not packable.
  int next(int state, int dir) const {
    const int p = state >> 2, r = state & 3;
    const auto [q, s] = neighbour[p][(r + 1 + dir) & 3];
    if (q < 0) return -1;
    // Entering q across its side s: that is the new cell's side 3 (moving along u) or 0 (along v).
    return 4 * q + (dir == 0 ? (s + 1) & 3 : s);
  }
};

/// How many cells a straight walk from each state takes along `dir` before the way ends or
/// comes back to where it started (a ring). An upper bound of a rectangle's width or height.
std::vector<int> run_lengths(const Grid& g, int dir) {
  const int states = static_cast<int>(g.neighbour.size()) * 4;
  std::vector<int> run(states, 0);
  std::vector<char> mark(states, 0);  // 0 new, 1 on the current walk, 2 done
  std::vector<int> path;
  for (int s0 = 0; s0 < states; ++s0) {
    if (mark[s0]) continue;
    path.clear();
    int s = s0;
    while (s >= 0 && mark[s] == 0) {
      mark[s] = 1;
      path.push_back(s);
      s = g.next(s, dir);
    }
    size_t first_before = path.size();  // states before this index get 1 + the next one's run
    int tail = 0;
    if (s >= 0 && mark[s] == 1) {  // the walk closed a ring at s
      const size_t start = static_cast<size_t>(std::find(path.begin(), path.end(), s) - path.begin());
      const int len = static_cast<int>(path.size() - start);
      for (size_t i = start; i < path.size(); ++i) run[path[i]] = len;
      first_before = start;
      tail = len;
    } else if (s >= 0) {
      tail = run[s];
    }
    for (size_t i = first_before; i-- > 0;) run[path[i]] = ++tail;
    for (int q : path) mark[q] = 2;
  }
  return run;
}

struct Rect {
  int w = 0, h = 0;
  std::vector<int> cells;  ///< states, cell (i, j) at j * w + i
};

/// The largest rectangle with its cell (0, 0) at `anchor`, over free patches only.
class RectFinder {
 public:
  RectFinder(const Grid& g, const std::vector<char>& taken) : g_(g), taken_(taken), seen_(taken.size(), 0) {}

  Rect largest(int anchor) {
    ++stamp_;
    Rect best;
    long long best_area = 0;
    std::vector<std::vector<int>> rows;
    int width = INT_MAX;
    for (int j = 0;; ++j) {
      std::vector<int> row;
      if (j == 0) {
        for (int s = anchor; usable(s) && static_cast<int>(row.size()) < width; s = g_.next(s, 0)) take(s, row);
      } else {
        const std::vector<int>& below = rows.back();
        for (int i = 0; i < width; ++i) {
          const int s = g_.next(below[i], 1);
          // The cell above (i, j-1) must also be the +u neighbour of (i-1, j): a grid, not a fold.
          if (!usable(s) || (i > 0 && g_.next(row.back(), 0) != s)) break;
          take(s, row);
        }
      }
      if (row.empty()) break;
      width = std::min(width, static_cast<int>(row.size()));
      rows.push_back(std::move(row));
      const long long area = static_cast<long long>(width) * (j + 1);
      if (area > best_area) {
        best_area = area;
        best.w = width;
        best.h = j + 1;
      }
    }
    for (int j = 0; j < best.h; ++j)
      best.cells.insert(best.cells.end(), rows[j].begin(), rows[j].begin() + best.w);
    return best;
  }

 private:
  bool usable(int s) const { return s >= 0 && !taken_[s >> 2] && seen_[s >> 2] != stamp_; }
  void take(int s, std::vector<int>& row) {
    seen_[s >> 2] = stamp_;
    row.push_back(s);
  }

  const Grid& g_;
  const std::vector<char>& taken_;
  std::vector<int> seen_;
  int stamp_ = 0;
};

/// Blossom of a cubic B-spline span: poles d[0..3] of the span [U[k], U[k+1]] of the flat knot
/// vector U, at (x1, x2, x3) (de Boor's algorithm with a different parameter per level).
Point3 blossom(const double* U, int k, const Point3* d, double x1, double x2, double x3) {
  Point3 p[4] = {d[0], d[1], d[2], d[3]};
  const double xs[3] = {x1, x2, x3};
  for (int r = 1; r <= 3; ++r)
    for (int i = 3; i >= r; --i) {
      const int g = k - 3 + i;
      const double a = (xs[r - 1] - U[g]) / (U[g + 4 - r] - U[g]);
      for (int c = 0; c < 3; ++c) p[i][c] = (1 - a) * p[i - 1][c] + a * p[i][c];
    }
  return p[3];
}

double distance(const Point3& a, const Point3& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

/// The span of the flat knot vector U (poles = U.size() - 4) holding parameter x: the largest
/// k <= poles - 1 with U[k] <= x (so a span's right end belongs to it only at the last span).
int span_at(const std::vector<double>& U, double x) {
  const int poles = static_cast<int>(U.size()) - 4;
  const int k = static_cast<int>(std::upper_bound(U.begin(), U.end(), x) - U.begin()) - 1;
  return std::clamp(k, 3, poles - 1);
}

/// A tensor B-spline (flat knot vectors, poles a * nv + b), here a quad's patch in a pack's
/// cell frame (knots over [0,1]) or the pack itself (knots over [0, w] x [0, h]).
struct Spline {
  std::vector<double> U, V;
  int nu = 0, nv = 0;
  std::vector<Point3> poles;

  const Point3& pole(int a, int b) const { return poles[static_cast<size_t>(a) * nv + b]; }

  /// The tensor blossom on span (ku, kv) at u-arguments xu and v-arguments xv.
  Point3 blossom2(int ku, int kv, const double xu[3], const double xv[3]) const {
    Point3 row[4];
    for (int al = 0; al < 4; ++al) {
      const Point3 d[4] = {pole(ku - 3 + al, kv - 3), pole(ku - 3 + al, kv - 2), pole(ku - 3 + al, kv - 1), pole(ku - 3 + al, kv)};
      row[al] = blossom(V.data(), kv, d, xv[0], xv[1], xv[2]);
    }
    return blossom(U.data(), ku, row, xu[0], xu[1], xu[2]);
  }

  /// The Bezier net (index x * 4 + y) over [u0, u1] x [v0, v1], which must lie in one span.
  void bezier(double u0, double u1, double v0, double v1, Point3 out[16]) const {
    if (nu == 4 && nv == 4 && U[3] == u0 && U[4] == u1 && V[3] == v0 && V[4] == v1) {
      std::copy(poles.begin(), poles.end(), out);  // one span, asked whole: its poles are the net
      return;
    }
    const int ku = span_at(U, (u0 + u1) / 2), kv = span_at(V, (v0 + v1) / 2);
    Point3 R[4][4];  // R[alpha][y]: u-pole ku-3+alpha, v Bezier point y
    for (int al = 0; al < 4; ++al) {
      const Point3 d[4] = {pole(ku - 3 + al, kv - 3), pole(ku - 3 + al, kv - 2), pole(ku - 3 + al, kv - 1), pole(ku - 3 + al, kv)};
      for (int y = 0; y < 4; ++y)
        R[al][y] = blossom(V.data(), kv, d, y > 2 ? v1 : v0, y > 1 ? v1 : v0, y > 0 ? v1 : v0);
    }
    for (int y = 0; y < 4; ++y) {
      const Point3 d[4] = {R[0][y], R[1][y], R[2][y], R[3][y]};
      for (int x = 0; x < 4; ++x) out[x * 4 + y] = blossom(U.data(), ku, d, x > 2 ? u1 : u0, x > 1 ? u1 : u0, x > 0 ? u1 : u0);
    }
  }
};

/// The interior knot values of a flat clamped knot vector.
std::vector<double> interior(const std::vector<double>& U) { return {U.begin() + 4, U.end() - 4}; }

/// A quad's patch seen from its corner r (packing.h: the cell frame), poles relative to origin.
Spline cell_spline(const NurbsPatch& p, int r, const Point3& origin) {
  const std::vector<double> Uq = p.knots_u.flat(), Vq = p.knots_v.flat();
  auto reversed = [](const std::vector<double>& K) {
    std::vector<double> out(K.size());
    for (size_t i = 0; i < K.size(); ++i) out[i] = 1 - K[K.size() - 1 - i];
    return out;
  };
  Spline c;
  switch (r & 3) {
    case 0: c.U = Uq; c.V = Vq; break;
    case 1: c.U = Vq; c.V = reversed(Uq); break;
    case 2: c.U = reversed(Uq); c.V = reversed(Vq); break;
    default: c.U = reversed(Vq); c.V = Uq; break;
  }
  const int nq = p.num_poles_u, mq = p.num_poles_v;
  c.nu = static_cast<int>(c.U.size()) - 4;
  c.nv = static_cast<int>(c.V.size()) - 4;
  c.poles.resize(p.poles.size());
  for (int a = 0; a < c.nu; ++a)
    for (int b = 0; b < c.nv; ++b) {
      int I, J;  // the quad's pole at cell pole (a, b): (s, t) = R(r)(x, y)
      switch (r & 3) {
        case 0: I = a; J = b; break;
        case 1: I = nq - 1 - b; J = a; break;
        case 2: I = nq - 1 - a; J = mq - 1 - b; break;
        default: I = b; J = mq - 1 - a; break;
      }
      const Point3& q = p.pole(I, J);
      c.poles[static_cast<size_t>(a) * c.nv + b] = {q[0] - origin[0], q[1] - origin[1], q[2] - origin[2]};
    }
  return c;
}

/// The surface of one rectangle: its quads' patches in the pack's frame (relative to
/// `origin`), then the B-spline with the union of their knot lines, minus the cell lines the
/// surface does not need, checked against every quad.
struct PackSurface {
  int w = 0, h = 0;
  std::vector<Spline> cells;  ///< cell (i, j) at j * w + i
  std::vector<std::vector<double>> col_knots, row_knots;  ///< per column / row: the quads' interior knots (local)
  Spline pack;

  const Spline& cell(int i, int j) const { return cells[static_cast<size_t>(j) * w + i]; }

  /// Largest third-derivative jump across each interior cell line (index 1 .. n-1), as a
  /// position at the pieces' scale: |d3 left - d3 right| h^3 / 6, h the smaller adjacent span.
  std::vector<double> jumps(bool across_u) const {
    const int n = across_u ? w : h, m = across_u ? h : w;
    std::vector<double> jump(n, 0.0), along;
    for (int line = 1; line < n; ++line)
      for (int o = 0; o < m; ++o) {
        const Spline& A = across_u ? cell(line - 1, o) : cell(o, line - 1);
        const Spline& B = across_u ? cell(line, o) : cell(o, line);
        const std::vector<double>& KA = across_u ? A.U : A.V;
        const std::vector<double>& KB = across_u ? B.U : B.V;
        const double ha = 1 - KA[KA.size() - 5], hb = KB[4];  // the spans next to the line
        // Both sides on the union of their knots along the line.
        along.clear();
        for (const Spline* c : {&A, &B}) {
          const std::vector<double>& K = across_u ? c->V : c->U;
          along.insert(along.end(), K.begin() + 4, K.end() - 4);
        }
        along.push_back(0);
        along.push_back(1);
        std::sort(along.begin(), along.end());
        along.erase(std::unique(along.begin(), along.end()), along.end());
        for (size_t q = 0; q + 1 < along.size(); ++q) {
          Point3 na[16], nb[16];
          if (across_u) {
            A.bezier(1 - ha, 1, along[q], along[q + 1], na);
            B.bezier(0, hb, along[q], along[q + 1], nb);
          } else {
            A.bezier(along[q], along[q + 1], 1 - ha, 1, na);
            B.bezier(along[q], along[q + 1], 0, hb, nb);
          }
          const double hm = std::min(ha, hb), sa = hm * hm * hm / (ha * ha * ha), sb = hm * hm * hm / (hb * hb * hb);
          for (int r = 0; r < 4; ++r) {
            Point3 d{};
            for (int c = 0; c < 3; ++c) {
              auto at = [&](const Point3* N, int k) { return across_u ? N[k * 4 + r][c] : N[r * 4 + k][c]; };
              const double da = at(na, 3) - 3 * at(na, 2) + 3 * at(na, 1) - at(na, 0);
              const double db = at(nb, 3) - 3 * at(nb, 2) + 3 * at(nb, 1) - at(nb, 0);
              d[c] = da * sa - db * sb;
            }
            jump[line] = std::max(jump[line], std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
          }
        }
      }
    return jump;
  }

  /// Flat knots over [0, n]: per cell line kept or not, and every quad's own knots.
  static std::vector<double> knots(int n, const std::vector<char>& keep, const std::vector<std::vector<double>>& own) {
    std::vector<double> U(4, 0.0);
    for (int i = 0; i < n; ++i) {
      if (i > 0 && keep[i]) U.push_back(i);
      for (double k : own[i]) U.push_back(i + k);
    }
    U.insert(U.end(), 4, static_cast<double>(n));
    return U;
  }

  /// A span of the pack in pole a's support, near the middle of its blossom arguments.
  static double inside(const std::vector<double>& U, int a) {
    for (int k : {a + 2, a + 1, a + 3, a})
      if (U[k] < U[k + 1]) return (U[k] + U[k + 1]) / 2;
    return U[a + 2];
  }

  void make_poles() {
    pack.nu = static_cast<int>(pack.U.size()) - 4;
    pack.nv = static_cast<int>(pack.V.size()) - 4;
    pack.poles.assign(static_cast<size_t>(pack.nu) * pack.nv, Point3{});
    std::vector<int> ci(pack.nu), cj(pack.nv), ku(pack.nu), kv(pack.nv);
    for (int a = 0; a < pack.nu; ++a) {
      const double x = inside(pack.U, a);
      ci[a] = std::min(static_cast<int>(x), w - 1);
    }
    for (int b = 0; b < pack.nv; ++b) {
      const double y = inside(pack.V, b);
      cj[b] = std::min(static_cast<int>(y), h - 1);
    }
    for (int a = 0; a < pack.nu; ++a)
      for (int b = 0; b < pack.nv; ++b) {
        const Spline& c = cell(ci[a], cj[b]);
        const int su = span_at(c.U, inside(pack.U, a) - ci[a]), sv = span_at(c.V, inside(pack.V, b) - cj[b]);
        const double xu[3] = {pack.U[a + 1] - ci[a], pack.U[a + 2] - ci[a], pack.U[a + 3] - ci[a]};
        const double xv[3] = {pack.V[b + 1] - cj[b], pack.V[b + 2] - cj[b], pack.V[b + 3] - cj[b]};
        pack.poles[static_cast<size_t>(a) * pack.nv + b] = c.blossom2(su, sv, xu, xv);
      }
  }

  /// Largest distance between a quad's Bezier pieces and the pack's over the same squares.
  double max_error() const {
    double worst = 0;
    std::vector<double> us, vs;
    for (int j = 0; j < h; ++j)
      for (int i = 0; i < w; ++i) {
        const Spline& c = cell(i, j);
        // The pack's spans inside this cell (they refine the quad's own).
        us.assign(std::lower_bound(pack.U.begin(), pack.U.end(), static_cast<double>(i)),
                  std::upper_bound(pack.U.begin(), pack.U.end(), static_cast<double>(i + 1)));
        vs.assign(std::lower_bound(pack.V.begin(), pack.V.end(), static_cast<double>(j)),
                  std::upper_bound(pack.V.begin(), pack.V.end(), static_cast<double>(j + 1)));
        us.push_back(i), us.push_back(i + 1), vs.push_back(j), vs.push_back(j + 1);
        std::sort(us.begin(), us.end());
        us.erase(std::unique(us.begin(), us.end()), us.end());
        std::sort(vs.begin(), vs.end());
        vs.erase(std::unique(vs.begin(), vs.end()), vs.end());
        for (size_t a = 0; a + 1 < us.size(); ++a)
          for (size_t b = 0; b + 1 < vs.size(); ++b) {
            Point3 mine[16], theirs[16];
            c.bezier(us[a] - i, us[a + 1] - i, vs[b] - j, vs[b + 1] - j, mine);
            pack.bezier(us[a], us[a + 1], vs[b], vs[b + 1], theirs);
            for (int k = 0; k < 16; ++k) worst = std::max(worst, distance(mine[k], theirs[k]));
          }
      }
    return worst;
  }
};

KnotVector knot_vector(const std::vector<double>& flat) {
  KnotVector kv;
  for (double x : flat) {
    if (!kv.knots.empty() && kv.knots.back() == x) {
      ++kv.mults.back();
    } else {
      kv.knots.push_back(x);
      kv.mults.push_back(1);
    }
  }
  return kv;
}

/// Builds the pack's patch; false if it does not reproduce its quads within `check`.
bool pack_surface(const PatchSet& quads, const Rect& rect, double knot_tolerance, double check, NurbsPatch& out,
                  long long& removed) {
  PackSurface S;
  S.w = rect.w;
  S.h = rect.h;
  const Point3 origin = quads.patches[rect.cells[0] >> 2].pole(0, 0);
  S.cells.reserve(rect.cells.size());
  for (int c : rect.cells) S.cells.push_back(cell_spline(quads.patches[c >> 2], c & 3, origin));
  // Each column's (row's) knots: the union of its quads' own, each value as often as the quad
  // that has it most often (a quad at an extraordinary vertex has double knots on its zone
  // lines, where Construction Q joins C1).
  std::vector<std::map<double, int>> col(S.w), row(S.h);
  for (int j = 0; j < S.h; ++j)
    for (int i = 0; i < S.w; ++i) {
      for (const auto& [K, into] : {std::pair{&S.cell(i, j).U, &col[i]}, std::pair{&S.cell(i, j).V, &row[j]}}) {
        std::map<double, int> own;
        for (double x : interior(*K)) ++own[x];
        for (const auto& [x, m] : own) (*into)[x] = std::max((*into)[x], m);
      }
    }
  auto flatten = [](const std::map<double, int>& mults) {
    std::vector<double> flat;
    for (const auto& [x, m] : mults) flat.insert(flat.end(), m, x);
    return flat;
  };
  S.col_knots.resize(S.w);
  S.row_knots.resize(S.h);
  for (int i = 0; i < S.w; ++i) S.col_knots[i] = flatten(col[i]);
  for (int j = 0; j < S.h; ++j) S.row_knots[j] = flatten(row[j]);
  const std::vector<double> ju = S.jumps(true), jv = S.jumps(false);
  std::vector<char> keep_u(S.w, 1), keep_v(S.h, 1);
  for (int i = 1; i < S.w; ++i) keep_u[i] = ju[i] > knot_tolerance;
  for (int j = 1; j < S.h; ++j) keep_v[j] = jv[j] > knot_tolerance;
  S.pack.U = PackSurface::knots(S.w, keep_u, S.col_knots);
  S.pack.V = PackSurface::knots(S.h, keep_v, S.row_knots);
  S.make_poles();
  if (S.max_error() > check) {
    // Blossoms far from their cell amplify rounding: keep every cell line instead.
    std::fill(keep_u.begin(), keep_u.end(), 1);
    std::fill(keep_v.begin(), keep_v.end(), 1);
    S.pack.U = PackSurface::knots(S.w, keep_u, S.col_knots);
    S.pack.V = PackSurface::knots(S.h, keep_v, S.row_knots);
    S.make_poles();
    if (S.max_error() > check) return false;
  }
  removed = std::count(keep_u.begin() + 1, keep_u.end(), 0) + std::count(keep_v.begin() + 1, keep_v.end(), 0);
  out = NurbsPatch{};
  out.kind = PatchKind::RegularBSpline;
  for (int c : rect.cells)
    if (quads.patches[c >> 2].kind == PatchKind::Pccm) out.kind = PatchKind::Pccm;
  out.knots_u = knot_vector(S.pack.U);
  out.knots_v = knot_vector(S.pack.V);
  out.num_poles_u = S.pack.nu;
  out.num_poles_v = S.pack.nv;
  out.poles.resize(S.pack.poles.size());
  for (size_t k = 0; k < S.pack.poles.size(); ++k)
    for (int c = 0; c < 3; ++c) out.poles[k][c] = S.pack.poles[k][c] + origin[c];
  return true;
}

/// Inserts knot x once into the cubic B-spline (flat knots U, poles P) (Boehm's algorithm).
void insert_knot(std::vector<double>& U, std::vector<Point3>& P, double x) {
  const int n = static_cast<int>(P.size());
  const int k = std::clamp(static_cast<int>(std::upper_bound(U.begin(), U.end(), x) - U.begin()) - 1, 3, n - 1);
  const int s = static_cast<int>(std::count(U.begin(), U.end(), x));
  std::vector<Point3> Q(n + 1);
  for (int i = 0; i <= k - 3; ++i) Q[i] = P[i];
  for (int i = k - s; i < n; ++i) Q[i + 1] = P[i];
  for (int i = k - 2; i <= k - s; ++i) {
    const double a = (x - U[i]) / (U[i + 3] - U[i]);
    for (int c = 0; c < 3; ++c) Q[i][c] = a * P[i][c] + (1 - a) * P[i - 1][c];
  }
  U.insert(U.begin() + k + 1, x);
  P.swap(Q);
}

/// The part [t0, t1] of a patch's side (side parameter, counter-clockwise) as a clamped cubic
/// curve over [0, 1] running counter-clockwise: the boundary row or column of poles, cut out
/// by knot insertion at its ends.
void side_curve(const NurbsPatch& p, int side, double t0, double t1, BoundaryCurve& curve) {
  const bool along_u = side % 2 == 0, backwards = side >= 2;
  std::vector<double> U = (along_u ? p.knots_u : p.knots_v).flat();
  std::vector<Point3> P;
  if (along_u) {
    const int j = side == 0 ? 0 : p.num_poles_v - 1;
    for (int i = 0; i < p.num_poles_u; ++i) P.push_back(p.pole(i, j));
  } else {
    const int i = side == 1 ? p.num_poles_u - 1 : 0;
    for (int j = 0; j < p.num_poles_v; ++j) P.push_back(p.pole(i, j));
  }
  const double lo = U.front(), hi = U.back();
  auto x_of = [&](double t) { return t == 0 ? (backwards ? hi : lo) : t == 1 ? (backwards ? lo : hi)
                                                                      : backwards ? hi - t * (hi - lo) : lo + t * (hi - lo); };
  // t is a ratio of whole quads (at / n); lo + t (hi - lo) can miss the knot it means by a
  // rounding error (23/42 * 42 = 22.999999999999996), and inserting that would put two knots
  // 4e-15 apart into the curve, which OCCT refuses. A value that close to a knot is that knot.
  const double snap = 1e-12 * (hi - lo);
  auto on_knot = [&](double x) {
    const auto it = std::lower_bound(U.begin(), U.end(), x - snap);
    return it != U.end() && std::abs(*it - x) <= snap ? *it : x;
  };
  const double xa = on_knot(std::min(x_of(t0), x_of(t1))), xb = on_knot(std::max(x_of(t0), x_of(t1)));
  for (double x : {xa, xb})
    if (x > lo && x < hi)
      while (std::count(U.begin(), U.end(), x) < 3) insert_knot(U, P, x);
  const int fa = static_cast<int>(std::lower_bound(U.begin(), U.end(), xa) - U.begin());
  const int fb = static_cast<int>(std::lower_bound(U.begin(), U.end(), xb) - U.begin());
  const int ia = xa == lo ? 0 : fa - 1, ib = xb == hi ? static_cast<int>(P.size()) - 1 : fb - 1;
  std::vector<Point3> poles(P.begin() + ia, P.begin() + ib + 1);
  std::vector<double> flat(4, 0.0);
  for (double u : U)
    if (u > xa && u < xb) flat.push_back((u - xa) / (xb - xa));
  flat.insert(flat.end(), 4, 1.0);
  if (backwards) {
    std::reverse(poles.begin(), poles.end());
    std::vector<double> r(flat.size());
    for (size_t i = 0; i < flat.size(); ++i) r[i] = 1 - flat[flat.size() - 1 - i];
    flat.swap(r);
  }
  curve.degree = 3;
  curve.poles = std::move(poles);
  curve.knots = knot_vector(flat);
}

/// Joins the curves between the same two faces, end to end, where no third face meets them:
/// consecutive pieces of one side of each face, oriented alike, with the same continuity, at
/// a corner no other curve uses. The joined curve is cut from a packed face's boundary.
void merge_curves(PackedSet& out, size_t corners) {
  PatchSet& ps = out.set;
  const int nc = static_cast<int>(ps.curves.size());
  std::vector<int> degree(corners, 0);
  for (const BoundaryCurve& c : ps.curves) {
    ++degree[c.corner0];
    ++degree[c.corner1];
  }
  // Curves with two uses, each a piece of a side, keyed by (face, side) of both uses.
  auto is_piece = [](const CurveUse& u) { return u.t0 != 0 || u.t1 != 1; };
  std::map<std::array<int, 5>, std::vector<int>> groups;
  for (int k = 0; k < nc; ++k) {
    BoundaryCurve& c = ps.curves[k];
    if (c.uses.empty() || c.uses.size() > 2) continue;
    // The same order of the two uses for every curve between the same sides.
    if (c.uses.size() == 2 &&
        std::make_pair(c.uses[1].patch, c.uses[1].side) < std::make_pair(c.uses[0].patch, c.uses[0].side))
      std::swap(c.uses[0], c.uses[1]);
    const CurveUse& A = c.uses[0];
    if (c.uses.size() == 1) {  // an open boundary along one side of a pack
      if (is_piece(A) && !ps.patches[A.patch].cells.empty())
        groups[{A.patch, A.side, -1, -1, static_cast<int>(c.continuity)}].push_back(k);
      continue;
    }
    const CurveUse& B = c.uses[1];
    if (!is_piece(A) || !is_piece(B) || A.reversed == B.reversed) continue;
    if (ps.patches[A.patch].cells.empty() && ps.patches[B.patch].cells.empty()) continue;
    groups[{A.patch, A.side, B.patch, B.side, static_cast<int>(c.continuity)}].push_back(k);
  }
  std::vector<BoundaryCurve> chains;
  std::vector<int> chain_of(nc, -1);
  for (auto& [key, list] : groups) {
    // Along the first use's side in its counter-clockwise order.
    std::sort(list.begin(), list.end(), [&](int a, int b) { return ps.curves[a].uses[0].t0 < ps.curves[b].uses[0].t0; });
    size_t i = 0;
    while (i < list.size()) {
      size_t j = i + 1;
      auto start_of = [&](int k) { const BoundaryCurve& c = ps.curves[k]; return c.uses[0].reversed ? c.corner1 : c.corner0; };
      auto end_of = [&](int k) { const BoundaryCurve& c = ps.curves[k]; return c.uses[0].reversed ? c.corner0 : c.corner1; };
      while (j < list.size()) {
        const BoundaryCurve& a = ps.curves[list[j - 1]];
        const BoundaryCurve& b = ps.curves[list[j]];
        const int joint = end_of(list[j - 1]);
        if (a.uses[0].t1 != b.uses[0].t0 || (a.uses.size() == 2 && b.uses[1].t1 != a.uses[1].t0) ||
            joint != start_of(list[j]) || degree[joint] != 2 || joint == start_of(list[i]))
          break;
        ++j;
      }
      if (j - i >= 2) {
        const BoundaryCurve& first = ps.curves[list[i]];
        const BoundaryCurve& last = ps.curves[list[j - 1]];
        BoundaryCurve m;
        m.corner0 = start_of(list[i]);
        m.corner1 = end_of(list[j - 1]);
        m.continuity = first.continuity;
        CurveUse A = first.uses[0];
        A.reversed = false;
        A.t1 = last.uses[0].t1;
        m.uses = {A};
        CurveUse B;
        if (first.uses.size() == 2) {
          B = first.uses[1];
          B.reversed = true;
          B.t0 = last.uses[1].t0;
          m.uses.push_back(B);
        }
        if (!ps.patches[A.patch].cells.empty()) {
          side_curve(ps.patches[A.patch], A.side, A.t0, A.t1, m);
        } else {  // along B's side, which runs the other way
          side_curve(ps.patches[B.patch], B.side, B.t0, B.t1, m);
          std::reverse(m.poles.begin(), m.poles.end());
          KnotVector r;
          for (size_t q = m.knots.knots.size(); q-- > 0;) {
            r.knots.push_back(1 - m.knots.knots[q]);
            r.mults.push_back(m.knots.mults[q]);
          }
          m.knots = r;
        }
        for (size_t q = i; q < j; ++q) chain_of[list[q]] = static_cast<int>(chains.size());
        chains.push_back(std::move(m));
      }
      i = j;
    }
  }
  if (chains.empty()) return;
  // Renumber: a chain takes the place of its first curve.
  std::vector<int> renumber(nc, -1), chain_index(chains.size(), -1);
  std::vector<BoundaryCurve> curves;
  std::vector<std::vector<int>> sources;
  for (int k = 0; k < nc; ++k) {
    const int ch = chain_of[k];
    if (ch < 0) {
      renumber[k] = static_cast<int>(curves.size());
      curves.push_back(std::move(ps.curves[k]));
      sources.push_back(std::move(out.source_curves[k]));
    } else {
      if (chain_index[ch] < 0) {
        chain_index[ch] = static_cast<int>(curves.size());
        curves.push_back(std::move(chains[ch]));
        sources.emplace_back();
      }
      renumber[k] = chain_index[ch];
      sources[chain_index[ch]].insert(sources[chain_index[ch]].end(), out.source_curves[k].begin(), out.source_curves[k].end());
    }
  }
  for (int& k : out.curve)
    if (k >= 0) k = renumber[k];
  ps.curves.swap(curves);
  out.source_curves.swap(sources);
}

}  // namespace

PackedSet unpacked(const PatchSet& quads) {
  PackedSet out;
  out.set = quads;
  out.place.resize(quads.patches.size());
  for (size_t p = 0; p < quads.patches.size(); ++p) out.place[p].patch = static_cast<int>(p);
  out.curve.resize(quads.curves.size());
  for (size_t k = 0; k < quads.curves.size(); ++k) out.curve[k] = static_cast<int>(k);
  out.source_curves.resize(quads.curves.size());
  for (size_t k = 0; k < quads.curves.size(); ++k) out.source_curves[k] = {static_cast<int>(k)};
  for (const NurbsPatch& p : quads.patches) out.total_poles += static_cast<long long>(p.poles.size());
  return out;
}

namespace {

PackedSet assemble(const PatchSet& quads, const std::vector<Rect>& rects, const std::vector<NurbsPatch>& surfaces,
                   const std::vector<char>& ok, const std::vector<long long>& removed,
                   const std::vector<int>& coarse_face, std::vector<int>& rect_of_patch);

PackedSet pack_impl(const PatchSet& quads, const std::vector<char>& patch_ok, const std::vector<char>& curve_ok,
                    const std::vector<int>& coarse_face, double knot_tolerance, double check, int max_edges) {
  const int np = static_cast<int>(quads.patches.size());
  // The grid: packable neighbours across packable curves.
  Grid g;
  g.neighbour.assign(np, {{{-1, -1}, {-1, -1}, {-1, -1}, {-1, -1}}});
  for (size_t k = 0; k < quads.curves.size(); ++k) {
    const BoundaryCurve& c = quads.curves[k];
    if (!curve_ok[k] || c.uses.size() != 2) continue;
    const CurveUse& A = c.uses[0];
    const CurveUse& B = c.uses[1];
    if (!patch_ok[A.patch] || !patch_ok[B.patch] || A.reversed == B.reversed) continue;  // orientations must agree
    if (A.t0 != 0 || A.t1 != 1 || B.t0 != 0 || B.t1 != 1) continue;
    g.neighbour[A.patch][A.side] = {B.patch, B.side};
    g.neighbour[B.patch][B.side] = {A.patch, A.side};
  }

  // Greedy, largest rectangle first. A state's key is an upper bound of its largest
  // rectangle's area (the straight runs along u and v); popped, the exact area is computed
  // and the state goes back in when the next key is larger (lazy evaluation).
  const std::vector<int> run_u = run_lengths(g, 0), run_v = run_lengths(g, 1);
  std::priority_queue<std::pair<long long, int>> queue;  // (area bound, -state): ties to the lowest state
  for (int p = 0; p < np; ++p)
    if (patch_ok[p])
      for (int r = 0; r < 4; ++r) queue.push({static_cast<long long>(run_u[4 * p + r]) * run_v[4 * p + r], -(4 * p + r)});
  std::vector<char> taken(np, 0);
  RectFinder finder(g, taken);
  std::vector<Rect> rects;
  while (!queue.empty()) {
    const int s = -queue.top().second;
    queue.pop();
    if (taken[s >> 2]) continue;
    Rect r = finder.largest(s);
    const long long area = static_cast<long long>(r.w) * r.h;
    if (!queue.empty() && area < queue.top().first) {
      queue.push({area, -s});
      continue;
    }
    for (int c : r.cells) taken[c >> 2] = 1;
    if (area >= 2) rects.push_back(std::move(r));
  }

  // Surfaces; a rectangle that does not reproduce its quads stays per quad. A pack with more
  // than max_edges edges on its boundary is cut into strips across its sides with the most
  // edges, and the output made again, until every pack has at most max_edges.
  std::vector<NurbsPatch> surfaces(rects.size());
  std::vector<char> ok(rects.size(), 0);
  std::vector<long long> removed(rects.size(), 0);
  int rejected = 0;
  size_t built = 0;  // rects[0, built) have their surfaces; strips cut from a pack come after them
  for (;;) {
    for (size_t i = built; i < rects.size(); ++i) {
      ok[i] = pack_surface(quads, rects[i], knot_tolerance, check, surfaces[i], removed[i]);
      if (!ok[i]) ++rejected;
    }
    built = rects.size();
    std::vector<int> rect_of_patch;
    PackedSet out = assemble(quads, rects, surfaces, ok, removed, coarse_face, rect_of_patch);
    out.rejected_packs = rejected;
    std::vector<std::pair<int, std::array<int, 4>>> over;  // (rect, edges per side)
    for (size_t pi = 0; pi < out.set.patches.size(); ++pi) {
      const NurbsPatch& p = out.set.patches[pi];
      if (p.cells.empty()) continue;
      std::array<int, 4> edges{};
      for (int s = 0; s < 4; ++s)
        edges[s] = p.split_sides[s].empty() ? (p.curves[s] >= 0 ? 1 : 0) : static_cast<int>(p.split_sides[s].size());
      if (edges[0] + edges[1] + edges[2] + edges[3] > max_edges) over.push_back({rect_of_patch[pi], edges});
    }
    if (over.empty()) return out;
    std::vector<char> drop(rects.size(), 0);
    for (const auto& [ri, edges] : over) {
      const Rect r = rects[ri];  // a copy: rects grows below
      drop[ri] = 1;
      // Across u (cutting the width) when the sides along u (0 and 2) hold more edges.
      const bool cut_u = r.h < 2 || (r.w >= 2 && edges[0] + edges[2] >= edges[1] + edges[3]);
      const int n = cut_u ? r.w : r.h, along = cut_u ? edges[0] + edges[2] : edges[1] + edges[3];
      const int room = std::max(1, max_edges - 4 - (cut_u ? edges[1] + edges[3] : edges[0] + edges[2]));
      const int parts = std::clamp((along + room - 1) / room, 2, n);
      for (int k = 0; k < parts; ++k) {
        const int a = static_cast<int>(static_cast<long long>(n) * k / parts);
        const int b = static_cast<int>(static_cast<long long>(n) * (k + 1) / parts);
        Rect part;
        part.w = cut_u ? b - a : r.w;
        part.h = cut_u ? r.h : b - a;
        if (part.w * part.h < 2) continue;  // a single quad stays alone
        for (int j = 0; j < part.h; ++j)
          for (int i = 0; i < part.w; ++i)
            part.cells.push_back(r.cells[static_cast<size_t>(cut_u ? j : a + j) * r.w + (cut_u ? a + i : i)]);
        rects.push_back(std::move(part));
      }
    }
    // Drop the rectangles that were cut (their surfaces with them).
    size_t kept = 0;
    for (size_t i = 0; i < drop.size(); ++i) {
      if (drop[i]) {
        if (!ok[i]) --rejected;
        continue;
      }
      if (kept != i) {
        rects[kept] = std::move(rects[i]);
        surfaces[kept] = std::move(surfaces[i]);
        ok[kept] = ok[i];
        removed[kept] = removed[i];
      }
      ++kept;
    }
    rects.erase(rects.begin() + kept, rects.begin() + drop.size());
    surfaces.resize(rects.size());
    ok.resize(rects.size(), 0);
    removed.resize(rects.size(), 0);
    built = kept;
  }
}

/// The output set of the chosen rectangles (those with ok[r] packed, with surfaces[r]).
PackedSet assemble(const PatchSet& quads, const std::vector<Rect>& rects, const std::vector<NurbsPatch>& surfaces,
                   const std::vector<char>& ok, const std::vector<long long>& removed,
                   const std::vector<int>& coarse_face, std::vector<int>& rect_of_patch) {
  const int np = static_cast<int>(quads.patches.size());
  PackedSet out;
  // Output patches in the order of each one's first quad.
  struct Member {
    int rect = -1, i = 0, j = 0, rotation = 0;
  };
  std::vector<Member> member(np);
  for (size_t ri = 0; ri < rects.size(); ++ri) {
    if (!ok[ri]) continue;
    const Rect& r = rects[ri];
    for (int j = 0; j < r.h; ++j)
      for (int i = 0; i < r.w; ++i) {
        const int s = r.cells[static_cast<size_t>(j) * r.w + i];
        member[s >> 2] = {static_cast<int>(ri), i, j, s & 3};
      }
  }
  out.place.resize(np);
  std::vector<int> output_of_rect(rects.size(), -1);
  PatchSet& ps = out.set;
  ps.model_size = quads.model_size;
  ps.closed = quads.closed;
  for (int p = 0; p < np; ++p) {
    const Member& m = member[p];
    if (m.rect < 0) {
      out.place[p] = {static_cast<int>(ps.patches.size()), 0, 0, 0};
      ps.patches.push_back(quads.patches[p]);
      continue;
    }
    if (output_of_rect[m.rect] < 0) {
      output_of_rect[m.rect] = static_cast<int>(ps.patches.size());
      const Rect& r = rects[m.rect];
      NurbsPatch pack = surfaces[m.rect];
      for (int j = 0; j < r.h; ++j)
        for (int i = 0; i < r.w; ++i) {
          const int s = r.cells[static_cast<size_t>(j) * r.w + i];
          const NurbsPatch& q = quads.patches[s >> 2];
          PatchCell cell;
          cell.base_face = q.base_faces.empty() ? -1 : q.base_faces.front();
          cell.coarse_face = coarse_face.empty() ? -1 : coarse_face[s >> 2];
          cell.u = i;
          cell.v = j;
          cell.rotation = s & 3;
          pack.cells.push_back(cell);
          pack.base_faces.insert(pack.base_faces.end(), q.base_faces.begin(), q.base_faces.end());
        }
      std::sort(pack.base_faces.begin(), pack.base_faces.end());
      pack.base_faces.erase(std::unique(pack.base_faces.begin(), pack.base_faces.end()), pack.base_faces.end());
      auto corner_of = [&](int i, int j, int c) {
        const int s = r.cells[static_cast<size_t>(j) * r.w + i];
        return quads.patches[s >> 2].corners[(c + (s & 3)) & 3];
      };
      pack.corners = {corner_of(0, 0, 0), corner_of(r.w - 1, 0, 1), corner_of(r.w - 1, r.h - 1, 2), corner_of(0, r.h - 1, 3)};
      pack.curves = {-1, -1, -1, -1};
      ps.patches.push_back(std::move(pack));
      rect_of_patch.resize(ps.patches.size(), -1);
      rect_of_patch.back() = m.rect;
      ++out.packs;
      out.packed_quads += r.w * r.h;
      out.removed_knots += removed[m.rect];
    }
    out.place[p] = {output_of_rect[m.rect], m.i, m.j, m.rotation};
  }

  // Curves: those inside a pack go; the others follow their uses into the output patches.
  out.curve.assign(quads.curves.size(), -1);
  for (NurbsPatch& p : ps.patches)
    if (!p.cells.empty()) p.split_sides = {};
  for (size_t k = 0; k < quads.curves.size(); ++k) {
    const BoundaryCurve& c = quads.curves[k];
    BoundaryCurve nc = c;
    nc.uses.clear();
    bool inside = !c.uses.empty();
    for (const CurveUse& use : c.uses) {
      const Member& m = member[use.patch];
      if (m.rect < 0) {
        CurveUse u = use;
        u.patch = out.place[use.patch].patch;
        nc.uses.push_back(u);
        inside = false;
        continue;
      }
      const Rect& r = rects[m.rect];
      const int side = (use.side - m.rotation + 4) & 3;
      const bool interior = (side == 0 && m.j > 0) || (side == 1 && m.i < r.w - 1) || (side == 2 && m.j < r.h - 1) ||
                            (side == 3 && m.i > 0);
      if (interior) continue;
      inside = false;
      CurveUse u;
      u.patch = output_of_rect[m.rect];
      u.side = side;
      u.reversed = use.reversed;
      const int n = side % 2 == 0 ? r.w : r.h;
      const int at = side == 0 ? m.i : side == 1 ? m.j : side == 2 ? r.w - 1 - m.i : r.h - 1 - m.j;
      u.t0 = static_cast<double>(at) / n;
      u.t1 = static_cast<double>(at + 1) / n;
      nc.uses.push_back(u);
    }
    if (inside) continue;
    out.curve[k] = static_cast<int>(ps.curves.size());
    out.source_curves.push_back({static_cast<int>(k)});
    ps.curves.push_back(std::move(nc));
  }
  merge_curves(out, quads.corners.size());
  // Sides: the output patches' curve indices. A side that is several curves (a pack's, a polar
  // cap's) is made again from the curves' uses, pieces joined above included.
  std::vector<std::array<char, 4>> pieced(ps.patches.size(), {{0, 0, 0, 0}});
  for (size_t pi = 0; pi < ps.patches.size(); ++pi) {
    NurbsPatch& p = ps.patches[pi];
    for (int s = 0; s < 4; ++s) {
      if (!p.cells.empty() || !p.split_sides[s].empty()) {
        pieced[pi][s] = 1;
        p.split_sides[s].clear();
        p.curves[s] = -1;
      } else if (p.curves[s] >= 0) {
        p.curves[s] = out.curve[p.curves[s]];
      }
    }
  }
  for (size_t k = 0; k < ps.curves.size(); ++k)
    for (const CurveUse& u : ps.curves[k].uses)
      if (pieced[u.patch][u.side]) ps.patches[u.patch].split_sides[u.side].push_back({static_cast<int>(k), u.reversed, u.t0, u.t1});
  for (size_t pi = 0; pi < ps.patches.size(); ++pi) {
    NurbsPatch& p = ps.patches[pi];
    for (int s = 0; s < 4; ++s) {
      std::vector<SidePiece>& pieces = p.split_sides[s];
      std::sort(pieces.begin(), pieces.end(), [](const SidePiece& a, const SidePiece& b) { return a.t0 < b.t0; });
      if (pieces.size() == 1 && pieces[0].t0 == 0 && pieces[0].t1 == 1) {
        p.curves[s] = pieces[0].curve;
        p.curve_reversed[s] = pieces[0].reversed;
        pieces.clear();
      }
    }
  }

  // Corners still used, renumbered.
  std::vector<int> corner_map(quads.corners.size(), -1);
  auto use_corner = [&](int& c) {
    if (c < 0) return;
    if (corner_map[c] < 0) {
      corner_map[c] = static_cast<int>(ps.corners.size());
      ps.corners.push_back(quads.corners[c]);
    }
    c = corner_map[c];
  };
  for (NurbsPatch& p : ps.patches)
    for (int& c : p.corners) use_corner(c);
  for (BoundaryCurve& c : ps.curves) {
    use_corner(c.corner0);
    use_corner(c.corner1);
  }
  for (const NurbsPatch& p : ps.patches) out.total_poles += static_cast<long long>(p.poles.size());
  return out;
}

}  // namespace

PackedSet pack_patches(const PatchBuild& b, int max_edges) {
  const PatchSet& ps = b.set;
  const SubdivLevel& la = b.refinement.levels[b.info.coarse_level];
  std::vector<char> patch_ok(ps.patches.size(), 0), curve_ok(ps.curves.size(), 0);
  for (size_t p = 0; p < ps.patches.size(); ++p) {
    const NurbsPatch& q = ps.patches[p];
    bool split = false;
    for (const auto& pieces : q.split_sides) split = split || !pieces.empty();
    bool simple = true;  // a regular patch's knots are simple inside (the limit is C2)
    for (const KnotVector* kv : {&q.knots_u, &q.knots_v})
      for (size_t i = 1; i + 1 < kv->mults.size(); ++i) simple = simple && kv->mults[i] == 1;
    // A quad at an extraordinary vertex joins across its sides that are C2 (never its fan
    // rays, which are G1): its own knots, nested towards the vertex and double on the zone
    // lines, run through its column and row of the pack.
    const bool kind_ok = q.kind == PatchKind::Pccm || (q.kind == PatchKind::RegularBSpline && simple);
    patch_ok[p] = b.coarse_face[p] >= 0 && kind_ok && q.weights.empty() &&
                  !split && q.knots_u.knots.front() == 0 && q.knots_u.knots.back() == 1 &&
                  q.knots_v.knots.front() == 0 && q.knots_v.knots.back() == 1;
  }
  for (size_t k = 0; k < ps.curves.size(); ++k) {
    const BoundaryCurve& c = ps.curves[k];
    if (c.uses.size() != 2 || c.continuity != Continuity::C2 || !patch_ok[c.uses[0].patch]) continue;
    const int F = b.coarse_face[c.uses[0].patch];
    const int e = la.mesh.corner_edge(la.mesh.face_begin(F) + c.uses[0].side);
    curve_ok[k] = la.edge_sharpness[e] == 0.0f;
  }
  return pack_impl(ps, patch_ok, curve_ok, b.coarse_face, tolerances::kKnotRemoval * ps.model_size,
                   tolerances::kSameSurface * ps.model_size, max_edges);
}

}  // namespace subd2nurbs
