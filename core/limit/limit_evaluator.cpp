#include "core/limit/limit_evaluator.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <cstdint>
#include <memory>
#include <mutex>
#include <unordered_map>

#include "core/limit/stam_eigen.h"
#include "core/mesh/marks.h"
#include "core/refine/quad_grid.h"
#include "core/util/bicubic.h"
#include "core/util/constants.h"
#include "core/util/parallel.h"

namespace subd2nurbs {

namespace {

constexpr float kInfSharp = static_cast<float>(kInfiniteSharpness);
constexpr int kMaxDepth = 100;       // refinement levels before a point is taken as its corner
constexpr int kNudgeExponent = 20;   // fallback derivatives: 2^-20 inside the face

bool infinite(float s) { return s >= kInfSharp; }
bool semi(float s) { return s > 0.0f && s < kInfSharp; }

// ---------------------------------------------------------------------------------------------
// Local derivatives and the affine parameter maps

struct Derivs {
  Point3 p{}, ds{}, dt{}, dss{}, dst{}, dtt{};
};

/// (s, t)_local = M (u, v) + c.
struct Affine {
  double m00 = 1, m01 = 0, m10 = 0, m11 = 1, c0 = 0, c1 = 0;
  /// Composition: first this, then `r` (a corner frame or a child map).
  Affine then(const Affine& r) const {
    Affine o;
    o.m00 = r.m00 * m00 + r.m01 * m10;
    o.m01 = r.m00 * m01 + r.m01 * m11;
    o.m10 = r.m10 * m00 + r.m11 * m10;
    o.m11 = r.m10 * m01 + r.m11 * m11;
    o.c0 = r.m00 * c0 + r.m01 * c1 + r.c0;
    o.c1 = r.m10 * c0 + r.m11 * c1 + r.c1;
    return o;
  }
  void apply(double s, double t, double& a, double& b) const {
    a = m00 * s + m01 * t + c0;
    b = m10 * s + m11 * t + c1;
  }
};

/// Frame of face corner k: (a, b) with a along the corner's outgoing edge and b towards the
/// previous corner, (0,0) at the corner. Face coordinates are those of corner 0.
Affine corner_frame(int k) {
  switch (k & 3) {
    case 0: return {1, 0, 0, 1, 0, 0};
    case 1: return {0, 1, -1, 0, 0, 1};   // a = t, b = 1 - s
    case 2: return {-1, 0, 0, -1, 1, 1};  // a = 1 - s, b = 1 - t
    default: return {0, -1, 1, 0, 1, 0};  // a = 1 - t, b = s
  }
}
/// Child quad at corner k of a quad: its coordinates are twice the corner frame's.
Affine child_map(int k) {
  Affine a = corner_frame(k);
  a.m00 *= 2; a.m01 *= 2; a.m10 *= 2; a.m11 *= 2; a.c0 *= 2; a.c1 *= 2;
  return a;
}

void axpy(Point3& y, double a, const Point3& x) {
  y[0] += a * x[0];
  y[1] += a * x[1];
  y[2] += a * x[2];
}

/// Derivatives with respect to (u, v) from those with respect to local (s, t) = M (u, v) + c.
LimitSample to_ptex(const Derivs& d, const Affine& A) {
  LimitSample o;
  o.p = d.p;
  axpy(o.du, A.m00, d.ds);
  axpy(o.du, A.m10, d.dt);
  axpy(o.dv, A.m01, d.ds);
  axpy(o.dv, A.m11, d.dt);
  axpy(o.duu, A.m00 * A.m00, d.dss);
  axpy(o.duu, 2 * A.m00 * A.m10, d.dst);
  axpy(o.duu, A.m10 * A.m10, d.dtt);
  axpy(o.duv, A.m00 * A.m01, d.dss);
  axpy(o.duv, A.m00 * A.m11 + A.m10 * A.m01, d.dst);
  axpy(o.duv, A.m10 * A.m11, d.dtt);
  axpy(o.dvv, A.m01 * A.m01, d.dss);
  axpy(o.dvv, 2 * A.m01 * A.m11, d.dst);
  axpy(o.dvv, A.m11 * A.m11, d.dtt);
  return o;
}

// ---------------------------------------------------------------------------------------------
// Uniform cubic B-spline patch of 16 points P[4a + b] (a along s)

void basis(double x, double N[4], double D[4], double DD[4]) { bspline_basis(x, N, D, DD); }

/// The bicubic sum over 16 points P[4a + b] (a along s) from the basis values and derivatives
/// in s and t.
template <class Pt>
Derivs tensor16(const Pt* P, const double Ns[4], const double Ds[4], const double DDs[4], const double Nt[4],
                const double Dt[4], const double DDt[4]) {
  Derivs d;
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b) {
      const auto& q = P[4 * a + b];
      for (int k = 0; k < 3; ++k) {
        const double c = q[k];
        d.p[k] += Ns[a] * Nt[b] * c;
        d.ds[k] += Ds[a] * Nt[b] * c;
        d.dt[k] += Ns[a] * Dt[b] * c;
        d.dss[k] += DDs[a] * Nt[b] * c;
        d.dst[k] += Ds[a] * Dt[b] * c;
        d.dtt[k] += Ns[a] * DDt[b] * c;
      }
    }
  return d;
}

template <class Pt>
Derivs bspline16(const Pt* P, double s, double t) {
  double Ns[4], Ds[4], DDs[4], Nt[4], Dt[4], DDt[4];
  basis(s, Ns, Ds, DDs);
  basis(t, Nt, Dt, DDt);
  return tensor16(P, Ns, Ds, DDs, Nt, Dt, DDt);
}

/// Basis functions of the semi-sharp cubic scheme on the span [0, 1] of four points
/// x_-1, x_0, x_1, x_2 whose points x_0 and x_1 carry crease sharpness s0, s1 (0: smooth):
/// the limit curve is sum N_i(x) x_i. One subdivision step keeps the span half [0, 1/2] or
/// [1/2, 1] that holds x: new edge points are midpoints; the new point at a vertex of
/// sharpness s is w x + (1 - w) (x_- + 6 x + x_+) / 8 with w = min(1, s), and its sharpness
/// drops by 1 (docs/math.md 9.7). Once neither end of the span is sharp, the span is a uniform
/// cubic B-spline span. With s0 = s1 = 0 this is basis().
void semi_sharp_basis(double x, double s0, double s1, double N[4], double D[4], double DD[4]) {
  double M[4][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};  // window = M * points
  double scale = 1;                                                          // d(window param)/dx
  while (s0 > 0 || s1 > 0) {
    const double w0 = std::min(1.0, std::max(0.0, s0)), w1 = std::min(1.0, std::max(0.0, s1));
    // The new points as combinations of the window x_-1 .. x_2, at -1/2, 0, 1/2, 1, 3/2.
    const double rows[5][4] = {{0.5, 0.5, 0, 0},
                               {(1 - w0) / 8, w0 + (1 - w0) * 0.75, (1 - w0) / 8, 0},
                               {0, 0.5, 0.5, 0},
                               {0, (1 - w1) / 8, w1 + (1 - w1) * 0.75, (1 - w1) / 8},
                               {0, 0, 0.5, 0.5}};
    const int first = x < 0.5 ? 0 : 1;  // the child window: rows first .. first + 3
    double C[4][4];
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) {
        double sum = 0;
        for (int k = 0; k < 4; ++k) sum += rows[first + r][k] * M[k][c];
        C[r][c] = sum;
      }
    std::copy(&C[0][0], &C[0][0] + 16, &M[0][0]);
    if (first == 0) {  // the child's x_0 is the vertex x_0 again
      x = 2 * x;
      s0 = s0 - 1;
      s1 = 0;  // the child's x_1 is the new edge point 1/2
    } else {
      x = 2 * x - 1;
      s0 = 0;  // the child's x_0 is the new edge point 1/2, its x_1 the vertex x_1
      s1 = s1 - 1;
    }
    scale *= 2;
  }
  double n[4], d[4], dd[4];
  basis(x, n, d, dd);
  for (int i = 0; i < 4; ++i) {
    N[i] = D[i] = DD[i] = 0;
    for (int r = 0; r < 4; ++r) {
      N[i] += n[r] * M[r][i];
      D[i] += d[r] * M[r][i];
      DD[i] += dd[r] * M[r][i];
    }
    D[i] *= scale;
    DD[i] *= scale * scale;
  }
}

// ---------------------------------------------------------------------------------------------
// Corner classification

enum class CornerKind : unsigned char { Regular, CreaseSide, CornerSide, SmoothEV, Other };

/// Every edge at v and v itself either smooth or infinitely sharp.
bool no_semi_sharp_at(const SubdivLevel& L, int v) {
  if (semi(L.vertex_sharpness[v])) return false;
  bool ok = true;
  for_each_vertex_edge(L.mesh, v, [&](int e, int) { ok = ok && !semi(L.edge_sharpness[e]); });
  return ok;
}

/// v interior, not sharp, no sharp incident edge, all faces quads (any valence).
bool smooth_quad_vertex(const SubdivLevel& L, int v) {
  const PolyMesh& m = L.mesh;
  if (m.is_boundary_vertex(v) || m.vertex_face_count(v) == 0 || L.vertex_sharpness[v] != 0.0f) return false;
  const int* c = m.vertex_corners(v);
  for (int i = 0, n = m.vertex_face_count(v); i < n; ++i) {
    if (m.face_size(m.corner_face(c[i])) != 4) return false;
    if (L.edge_sharpness[m.corner_edge(c[i])] != 0.0f) return false;
  }
  return true;
}

/// Kind of corner h (a halfedge of quad face f leaving the corner vertex).
CornerKind classify_corner(const SubdivLevel& L, int h) {
  const PolyMesh& m = L.mesh;
  const int v = m.corner_vertex(h);
  const int hp = m.prev(h);
  const float s_out = L.edge_sharpness[m.corner_edge(h)];
  const float s_in = L.edge_sharpness[m.corner_edge(hp)];
  if (s_out == 0.0f && s_in == 0.0f) {
    if (!smooth_quad_vertex(L, v)) return CornerKind::Other;
    const int n = m.vertex_face_count(v);
    if (n == 4) return CornerKind::Regular;
    return n >= 3 ? CornerKind::SmoothEV : CornerKind::Other;
  }
  if (!no_semi_sharp_at(L, v)) return CornerKind::Other;
  if (infinite(s_out) && infinite(s_in)) {
    return vertex_rule(L, v) == VertexRule::Corner ? CornerKind::CornerSide : CornerKind::Other;
  }
  // One face edge infinitely sharp, the other smooth: a crease (or boundary) vertex with two
  // faces on this side, both quads.
  if (L.vertex_sharpness[v] != 0.0f) return CornerKind::Other;
  int sharp = 0;
  for_each_vertex_edge(m, v, [&](int e, int) { sharp += infinite(L.edge_sharpness[e]) ? 1 : 0; });
  if (sharp != 2) return CornerKind::Other;
  int other;  // the other face's edge at v, across the smooth face edge
  if (s_out == 0.0f) {
    const int t = m.twin(h);  // runs into v in the neighbouring face
    if (t < 0 || m.face_size(m.corner_face(t)) != 4) return CornerKind::Other;
    other = m.corner_edge(m.next(t));
  } else {
    const int t = m.twin(hp);  // leaves v in the neighbouring face
    if (t < 0 || m.face_size(m.corner_face(t)) != 4) return CornerKind::Other;
    other = m.corner_edge(m.prev(t));
  }
  return infinite(L.edge_sharpness[other]) ? CornerKind::CreaseSide : CornerKind::Other;
}

/// Quad f's grid (gather_quad_grid) with the diagonal points of the Regular corners.
void gather_grid(const SubdivLevel& L, const std::vector<Point3>& P, int f, const CornerKind kind[4], QuadGrid& g) {
  const bool diagonal[4] = {kind[0] == CornerKind::Regular, kind[1] == CornerKind::Regular,
                            kind[2] == CornerKind::Regular, kind[3] == CornerKind::Regular};
  gather_quad_grid(L, P, f, diagonal, g);
}

// ---------------------------------------------------------------------------------------------
// Per-face evaluation data (cached for base faces)

/// The 16 B-spline points of each of the 3 tiles of one level of a Stam face (level m - 1's
/// configuration: stam_eval).
using StamTiles = std::array<std::array<Point3, 16>, 3>;

/// A Stam face's tiles level by level, filled as samples ask for deeper levels (faces at a
/// vertex of high valence: a sample costs O(K) per level to go down, K = 2n + 1, and the same
/// levels are gone down again for every sample of the face; at valence 1024 that made the
/// quality stage's exact limit O(n^2) per fan). The table is computed by the same operations
/// in the same order as stam_eval's walk, so its values are the same to the bit.
struct StamLevelTable {
  std::mutex mutex;
  std::vector<double> cj;    ///< ring in the eigenbasis at the next level to add (cj[3 i + c])
  double o[7][3] = {};       ///< outer points at that level
  std::vector<StamTiles> tiles;  ///< per level m - 1 = 0, 1, ...
};

/// A Stam face's data (prepare: one extraordinary corner).
struct StamData {
  std::shared_ptr<const StamEigen> eig;
  Eigen::Matrix<double, Eigen::Dynamic, 3> ring;  // ring points in sector order
  Eigen::Matrix<double, Eigen::Dynamic, 3> chat;  // V^-1 ring
  Eigen::Matrix<double, 7, 3> outer = Eigen::Matrix<double, 7, 3>::Zero();  // outer points
  Point3 limit{};  // limit position of the EV; ring, chat and outer are relative to it
  /// Above this valence the tiles are kept level by level (StamLevelTable); below it a
  /// sample's walk is cheap and a table per face would cost more memory than it saves time.
  static constexpr int kTableValence = 16;
  std::unique_ptr<StamLevelTable> table;  ///< set by prepare (kept) when eig->n > kTableValence
};

struct Prepared {
  LimitMethod method = LimitMethod::Refined;  // Regular, Stam, SemiSharp, or Refined (= not prepared)
  std::array<Point3, 16> grid{};              // Regular, SemiSharp: the grid's points, index 4a + b
  int across = 0;                             // SemiSharp: crease lines crossed along s (0) or t (1)
  std::array<double, 2> sharpness{};          // SemiSharp: of the lines at 0 and 1 of that parameter
  int corner = 0;                             // Stam: the EV's corner of the face
  std::shared_ptr<const StamData> stam;       // Stam: the eigenbasis data (apart: few faces need it)
};

/// A quad whose 4x4 grid is regular (its corners interior, valence 4, untagged, between quads)
/// and whose tagged edges among the 12 at its corners lie on semi-sharp crease lines of the grid
/// in one direction, one sharpness along each line's three edges. Subdivision there is the
/// tensor product of cubic B-spline subdivision along the lines and semi_sharp_basis's curve
/// scheme across them (docs/math.md 9.7), so the limit is the closed-form product. Anything
/// else (crossing lines, a sharpness changing along a line, infinitely sharp edges, vertex tags):
/// method Refined.
Prepared prepare_semi_sharp(const SubdivLevel& L, const std::vector<Point3>& P, int f) {
  Prepared out;
  const PolyMesh& m = L.mesh;
  CornerKind kind[4];
  for (int k = 0; k < 4; ++k) {
    const int v = m.corner_vertex(m.face_begin(f) + k);
    if (m.is_boundary_vertex(v) || m.vertex_face_count(v) != 4 || L.vertex_sharpness[v] != 0.0f) return out;
    const int* c = m.vertex_corners(v);
    for (int i = 0; i < 4; ++i)
      if (m.face_size(m.corner_face(c[i])) != 4) return out;
    kind[k] = CornerKind::Regular;
  }
  QuadGrid g;
  gather_grid(L, P, f, kind, g);
  for (int i = 0; i < 16; ++i)
    if (g.vertex[i] < 0) return out;  // a phantom: an infinitely sharp side
  // The sharpness of the three edges of grid line `line` (0 or 1) along s (rows) or t.
  auto line_sharpness = [&](bool along_s, int line, float& sharpness) {
    for (int k = -1; k <= 1; ++k) {
      const int a = along_s ? g.vertex_at(k, line) : g.vertex_at(line, k);
      const int b = along_s ? g.vertex_at(k + 1, line) : g.vertex_at(line, k + 1);
      const int e = m.find_edge(a, b);
      if (e < 0 || infinite(L.edge_sharpness[e])) return false;
      if (k == -1) sharpness = L.edge_sharpness[e];
      if (L.edge_sharpness[e] != sharpness) return false;
    }
    return true;
  };
  float row[2], col[2];
  for (int l = 0; l < 2; ++l)
    if (!line_sharpness(true, l, row[l]) || !line_sharpness(false, l, col[l])) return out;
  const bool rows = row[0] > 0 || row[1] > 0, cols = col[0] > 0 || col[1] > 0;
  if (rows == cols) return out;  // crossing lines meet at a corner rule
  out.method = LimitMethod::SemiSharp;
  std::copy(g.P, g.P + 16, out.grid.begin());
  out.across = rows ? 1 : 0;
  out.sharpness = rows ? std::array<double, 2>{row[0], row[1]} : std::array<double, 2>{col[0], col[1]};
  return out;
}

/// A face whose limit is a tensor sum over its 16 grid points (Regular or SemiSharp).
bool on_grid(const Prepared& pr) {
  return pr.method == LimitMethod::Regular || pr.method == LimitMethod::SemiSharp;
}

/// The basis in s (axis 0) or t (axis 1) of a Regular or SemiSharp face.
void axis_basis(const Prepared& pr, int axis, double x, double N[4], double D[4], double DD[4]) {
  if (pr.method == LimitMethod::SemiSharp && pr.across == axis)
    semi_sharp_basis(x, pr.sharpness[0], pr.sharpness[1], N, D, DD);
  else
    basis(x, N, D, DD);
}

/// The bases in s and t of a Regular or SemiSharp face.
void grid_bases(const Prepared& pr, double s, double t, double Ns[4], double Ds[4], double DDs[4], double Nt[4],
                double Dt[4], double DDt[4]) {
  axis_basis(pr, 0, s, Ns, Ds, DDs);
  axis_basis(pr, 1, t, Nt, Dt, DDt);
}

/// `kept`: the result is kept for many samples (the evaluator's caches), so a Stam face of high
/// valence gets its table of levels (StamLevelTable); a fresh one for a single sample does not.
Prepared prepare(const SubdivLevel& L, const std::vector<Point3>& P, int f, bool kept = false) {
  Prepared out;
  const PolyMesh& m = L.mesh;
  if (m.face_size(f) != 4) return out;
  CornerKind kind[4];
  int ev = -1, bad = 0;
  for (int k = 0; k < 4; ++k) {
    kind[k] = classify_corner(L, m.face_begin(f) + k);
    if (kind[k] == CornerKind::SmoothEV) ev = ev < 0 ? k : 4;
    if (kind[k] == CornerKind::Other) ++bad;
  }
  if (bad > 0) return prepare_semi_sharp(L, P, f);
  if (ev == 4) return out;
  QuadGrid g;
  gather_grid(L, P, f, kind, g);
  if (ev < 0) {
    for (int i = 0; i < 16; ++i)
      if (!g.have[i]) throw std::logic_error("limit: regular grid incomplete");
    out.method = LimitMethod::Regular;
    std::copy(g.P, g.P + 16, out.grid.begin());
    return out;
  }
  for (int k = 0; k < 4; ++k)
    if (k != ev && kind[k] != CornerKind::Regular) return out;  // Stam needs three regular corners
  const int h = m.face_begin(f) + ev;
  const int v = m.corner_vertex(h);
  const int n = m.vertex_face_count(v);
  const int* fan = m.vertex_corners(v);
  int s0 = -1;
  for (int r = 0; r < n; ++r)
    if (fan[r] == h) s0 = r;
  if (s0 < 0) throw std::logic_error("limit: face corner not in its vertex fan");
  out.method = LimitMethod::Stam;
  out.corner = ev;
  auto stam = std::make_shared<StamData>();
  StamData& st = *stam;
  st.eig = stam_eigen(n);
  st.ring.resize(2 * n + 1, 3);
  for (int c = 0; c < 3; ++c) st.ring(0, c) = P[v][c];
  for (int r = 0; r < n; ++r) {
    const int cr = fan[(s0 + r) % n];
    const Point3& e = P[m.to_vertex(cr)];
    const Point3& d = P[m.to_vertex(m.next(cr))];
    for (int c = 0; c < 3; ++c) {
      st.ring(1 + r, c) = e[c];
      st.ring(1 + n + r, c) = d[c];
    }
  }
  static const int kOuter[7][2] = {{2, -1}, {2, 0}, {2, 1}, {2, 2}, {1, 2}, {0, 2}, {-1, 2}};
  for (int o = 0; o < 7; ++o) {
    int i, j;
    corner_to_grid(ev, kOuter[o][0], kOuter[o][1], i, j);
    if (!g.has(i, j)) throw std::logic_error("limit: Stam configuration incomplete");
    for (int c = 0; c < 3; ++c) st.outer(o, c) = g.at(i, j)[c];
  }
  // Work relative to the EV's limit point and drop the eigenvalue-1 component exactly: the
  // derivatives are scaled by 2^m (m up to ~1000 for tiny u, v), and a rounding-level constant
  // left in the points would be amplified by that.
  const std::vector<double>& w = st.eig->limit_weights;
  for (int i = 0; i < 2 * n + 1; ++i)
    for (int c = 0; c < 3; ++c) st.limit[c] += w[i] * st.ring(i, c);
  for (int c = 0; c < 3; ++c) {
    st.ring.col(c).array() -= st.limit[c];
    st.outer.col(c).array() -= st.limit[c];
  }
  st.chat = st.eig->Vinv * st.ring;
  st.chat.row(0).setZero();  // stam_eigen puts eigenvalue 1 first
  if (kept && n > StamData::kTableValence) st.table = std::make_unique<StamLevelTable>();
  out.stam = std::move(stam);
  return out;
}

/// One level down the Stam walk: o <- W cj + S12 o, then cj <- Lambda cj.
void stam_step(const StamEigen& E, double* cj, double (&o)[7][3]) {
  const int K = E.K;
  double next[7][3];
  for (int r = 0; r < 7; ++r) {
    double acc[3] = {0, 0, 0};
    for (int i = 0; i < K; ++i) {
      const double w = E.W(r, i);
      acc[0] += w * cj[3 * i];
      acc[1] += w * cj[3 * i + 1];
      acc[2] += w * cj[3 * i + 2];
    }
    for (int q = 0; q < 7; ++q) {
      const double w = E.S12(r, q);
      acc[0] += w * o[q][0];
      acc[1] += w * o[q][1];
      acc[2] += w * o[q][2];
    }
    next[r][0] = acc[0];
    next[r][1] = acc[1];
    next[r][2] = acc[2];
  }
  std::copy(&next[0][0], &next[0][0] + 21, &o[0][0]);
  for (int i = 0; i < K; ++i) {
    const double l = E.lambda(i);
    cj[3 * i] *= l;
    cj[3 * i + 1] *= l;
    cj[3 * i + 2] *= l;
  }
}

/// The 16 B-spline points of `tile` from a level's configuration (cj, o).
void stam_tile(const StamEigen& E, int tile, const double* cj, const double (&o)[7][3], std::array<Point3, 16>& Pt) {
  const int K = E.K;
  const Eigen::MatrixXd& TR = E.tile_ring_V[tile];
  const Eigen::MatrixXd& TO = E.tile_outer[tile];
  for (int r = 0; r < 16; ++r) {
    double acc[3] = {0, 0, 0};
    for (int i = 0; i < K; ++i) {
      const double w = TR(r, i);
      acc[0] += w * cj[3 * i];
      acc[1] += w * cj[3 * i + 1];
      acc[2] += w * cj[3 * i + 2];
    }
    for (int q = 0; q < 7; ++q) {
      const double w = TO(r, q);
      acc[0] += w * o[q][0];
      acc[1] += w * o[q][1];
      acc[2] += w * o[q][2];
    }
    Pt[r] = {acc[0], acc[1], acc[2]};
  }
}

/// The level's start: ring in the eigenbasis and outer points of the face (level 0).
void stam_start(const StamData& st, double* cj, double (&o)[7][3]) {
  for (int i = 0; i < st.eig->K; ++i)
    for (int c = 0; c < 3; ++c) cj[3 * i + c] = st.chat(i, c);
  for (int r = 0; r < 7; ++r)
    for (int c = 0; c < 3; ++c) o[r][c] = st.outer(r, c);
}

/// Stam evaluation at corner-frame (a, b) != (0, 0); derivatives w.r.t. (a, b).
Derivs stam_eval(const Prepared& pr, double a, double b) {
  const StamData& st = *pr.stam;
  const StamEigen& E = *st.eig;
  const double mx = std::max(a, b);
  int e;
  std::frexp(mx, &e);
  const int mlev = std::max(1, 1 - e);  // 2^m max(a, b) in [1, 2)
  const double X = std::ldexp(a, mlev), Y = std::ldexp(b, mlev);
  int tile;
  double x, y;
  if (Y < 1) { tile = 0; x = X - 1; y = Y; }
  else if (X < 1) { tile = 2; x = X; y = Y - 1; }
  else { tile = 1; x = X - 1; y = Y - 1; }
  // Level m-1 configuration: ring in the eigenbasis (c_j = Lambda^j c^), outer points by the
  // recurrence o_{j+1} = W c_j + S12 o_j. Plain loops over a per-thread buffer: no allocation
  // per query (Eigen's dynamic products allocate temporaries).
  std::array<Point3, 16> Pt;
  if (st.table) {
    StamLevelTable& T = *st.table;
    const std::lock_guard<std::mutex> lock(T.mutex);
    if (T.tiles.empty()) {
      T.cj.resize(static_cast<size_t>(3) * E.K);
      stam_start(st, T.cj.data(), T.o);
    }
    while (static_cast<int>(T.tiles.size()) < mlev) {
      if (!T.tiles.empty()) stam_step(E, T.cj.data(), T.o);
      StamTiles level;
      for (int k = 0; k < 3; ++k) stam_tile(E, k, T.cj.data(), T.o, level[k]);
      T.tiles.push_back(level);
    }
    Pt = T.tiles[static_cast<size_t>(mlev - 1)][static_cast<size_t>(tile)];
  } else {
    thread_local std::vector<double> buffer;
    buffer.resize(static_cast<size_t>(3) * E.K);
    double* cj = buffer.data();  // cj[3 * i + c]
    double o[7][3];
    stam_start(st, cj, o);
    for (int j = 0; j + 1 < mlev; ++j) stam_step(E, cj, o);
    stam_tile(E, tile, cj, o, Pt);
  }
  Derivs d = bspline16(Pt.data(), x, y);
  for (int k = 0; k < 3; ++k) d.p[k] += st.limit[k];
  const double s1 = std::ldexp(1.0, mlev), s2 = s1 * s1;
  for (int k = 0; k < 3; ++k) {
    d.ds[k] *= s1; d.dt[k] *= s1;
    d.dss[k] *= s2; d.dst[k] *= s2; d.dtt[k] *= s2;
  }
  return d;
}

/// At the extraordinary vertex itself: limit position and edge-ray tangents (docs/math.md 2.2, 9.4).
Derivs stam_at_vertex(const Prepared& pr) {
  const StamData& st = *pr.stam;
  const int n = st.eig->n;
  Derivs d;
  const double cn = std::cos(2 * kPi / n);
  const double An = 1 + cn + std::cos(kPi / n) * std::sqrt(2 * (9 + cn));
  Point3 T1{}, T2{};
  for (int r = 0; r < n; ++r) {
    const double th = 2 * kPi * r / n, th1 = 2 * kPi * (r + 1) / n;
    for (int c = 0; c < 3; ++c) {
      T1[c] += An * std::cos(th) * st.ring(1 + r, c) + (std::cos(th) + std::cos(th1)) * st.ring(1 + n + r, c);
      T2[c] += An * std::sin(th) * st.ring(1 + r, c) + (std::sin(th) + std::sin(th1)) * st.ring(1 + n + r, c);
    }
  }
  d.p = st.limit;
  const double ca = std::cos(2 * kPi / n), sa = std::sin(2 * kPi / n), sc = 1.0 / (3 * n);
  for (int c = 0; c < 3; ++c) {
    d.ds[c] = sc * T1[c];
    d.dt[c] = sc * (ca * T1[c] + sa * T2[c]);
  }
  return d;
}

void finish_sample_local(LimitSample& o);

/// A sample from its position and derivatives, finished (finish_sample).
LimitSample finished_sample(const Point3& p, const Point3& du, const Point3& dv, const Point3& duu,
                            const Point3& duv, const Point3& dvv) {
  LimitSample s;
  s.p = p;
  s.du = du;
  s.dv = dv;
  s.duu = duu;
  s.duv = duv;
  s.dvv = dvv;
  finish_sample_local(s);
  return s;
}

/// Next to a valence-3 vertex the derivatives vanish like (2 lambda)^m and underflow for
/// u, v below about 1e-250: then the normal is the vertex's limit normal (its limit).
void stam_normal_fallback(const Prepared& pr, LimitSample& out) {
  if (out.normal[0] != 0 || out.normal[1] != 0 || out.normal[2] != 0) return;
  const Derivs at = stam_at_vertex(pr);
  LimitSample t;
  t.du = at.ds;
  t.dv = at.dt;
  finish_sample_local(t);
  out.normal = t.normal;
  out.exact_derivatives = false;
}

Derivs eval_prepared(const Prepared& pr, double s, double t, bool* singular) {
  if (on_grid(pr)) {
    double Ns[4], Ds[4], DDs[4], Nt[4], Dt[4], DDt[4];
    grid_bases(pr, s, t, Ns, Ds, DDs, Nt, Dt, DDt);
    return tensor16(pr.grid.data(), Ns, Ds, DDs, Nt, Dt, DDt);
  }
  double a, b;
  corner_frame(pr.corner).apply(s, t, a, b);
  if (a <= 0 && b <= 0) {
    *singular = true;
    return stam_at_vertex(pr);
  }
  return stam_eval(pr, std::max(a, 0.0), std::max(b, 0.0));
}

// ---------------------------------------------------------------------------------------------
// Local refinement: the 2-ring of a face, refined once

/// The 2-ring cannot be cut out as a mesh of its own (degenerate topology such as two edges
/// joining the same two vertices next to folded valence-2 vertices).
struct CannotCutOut {};

struct LocalLevel {
  SubdivLevel level;
  std::vector<Point3> pos;
};

LocalLevel extract_two_ring_impl(const SubdivLevel& L, const std::vector<Point3>& P, int f);

/// Cuts out every face touching a vertex of a face touching f (f becomes local face 0, same
/// corner order). Outer vertices whose local faces form several fans are split, one copy per
/// fan; their values are wrong after refinement anyway and are never used for f's children.
LocalLevel extract_two_ring(const SubdivLevel& L, const std::vector<Point3>& P, int f) {
  try {
    return extract_two_ring_impl(L, P, f);
  } catch (const InvalidMeshError&) {
    throw CannotCutOut{};
  }
}

LocalLevel extract_two_ring_impl(const SubdivLevel& L, const std::vector<Point3>& P, int f) {
  const PolyMesh& m = L.mesh;
  thread_local std::vector<int> face_store, vertex_store;
  Marks face_local(face_store, m.num_faces());
  // Per vertex: -1 outer (or not in the ring), 0 inner, 1 + its local index once numbered.
  Marks vertex_mark(vertex_store, m.num_vertices());
  std::vector<int> faces;
  auto add_face = [&](int g) {
    if (face_local.set(g, static_cast<int>(faces.size()))) faces.push_back(g);
  };
  auto faces_at = [&](int v, auto&& fn) {
    const int* c = m.vertex_corners(v);
    for (int i = 0, n = m.vertex_face_count(v); i < n; ++i) fn(m.corner_face(c[i]));
  };
  add_face(f);
  std::vector<int> inner;  // V1: vertices of faces touching f
  for (int h = m.face_begin(f); h < m.face_end(f); ++h)
    faces_at(m.corner_vertex(h), [&](int g) {
      for (int k = m.face_begin(g); k < m.face_end(g); ++k)
        if (vertex_mark.set(m.corner_vertex(k), 0)) inner.push_back(m.corner_vertex(k));
    });
  for (int v : inner) faces_at(v, add_face);

  // Local vertices: inner vertices once; outer vertices once per fan of local faces.
  std::vector<int> local_orig;
  std::vector<int> sizes, idx;
  struct Occ { int orig; int face_pos; int prev, next; };
  std::vector<Occ> occ;
  for (int lf = 0; lf < static_cast<int>(faces.size()); ++lf) {
    const int g = faces[lf];
    sizes.push_back(m.face_size(g));
    for (int h = m.face_begin(g); h < m.face_end(g); ++h) {
      const int v = m.corner_vertex(h);
      if (vertex_mark.get(v) >= 0) {
        if (vertex_mark.get(v) == 0) {
          vertex_mark.put(v, 1 + static_cast<int>(local_orig.size()));
          local_orig.push_back(v);
        }
        idx.push_back(vertex_mark.get(v) - 1);
      } else {
        occ.push_back({v, static_cast<int>(idx.size()), m.corner_vertex(m.prev(h)), m.to_vertex(h)});
        idx.push_back(-1);
      }
    }
  }
  // The occurrences of each outer vertex, joined where two of them share a neighbour.
  std::stable_sort(occ.begin(), occ.end(), [](const Occ& a, const Occ& b) { return a.orig < b.orig; });
  std::vector<int> parent, comp_local;
  for (size_t first = 0; first < occ.size();) {
    size_t last = first;
    while (last < occ.size() && occ[last].orig == occ[first].orig) ++last;
    const int k = static_cast<int>(last - first);
    parent.resize(k);
    for (int i = 0; i < k; ++i) parent[i] = i;
    auto find = [&](int i) {
      while (parent[i] != i) i = parent[i] = parent[parent[i]];
      return i;
    };
    for (int i = 0; i < k; ++i)
      for (int j = i + 1; j < k; ++j) {
        const Occ& a = occ[first + i];
        const Occ& b = occ[first + j];
        if (a.prev == b.next || a.next == b.prev || a.prev == b.prev || a.next == b.next)
          parent[find(i)] = find(j);
      }
    comp_local.assign(k, -1);
    for (int i = 0; i < k; ++i) {
      int& local = comp_local[find(i)];
      if (local < 0) {
        local = static_cast<int>(local_orig.size());
        local_orig.push_back(occ[first].orig);
      }
      idx[occ[first + i].face_pos] = local;
    }
    first = last;
  }
  LocalLevel out;
  const int nv = static_cast<int>(local_orig.size());
  out.level.mesh = PolyMesh::build(nv, sizes, idx);
  const PolyMesh& lm = out.level.mesh;
  out.level.options = L.options;
  out.level.vertex_sharpness.resize(nv);
  out.pos.resize(nv);
  for (int v = 0; v < nv; ++v) {
    out.level.vertex_sharpness[v] = L.vertex_sharpness[local_orig[v]];
    out.pos[v] = P[local_orig[v]];
  }
  out.level.face_hole.resize(faces.size());
  for (size_t lf = 0; lf < faces.size(); ++lf) out.level.face_hole[lf] = L.face_hole[faces[lf]];
  out.level.edge_sharpness.resize(lm.num_edges());
  for (int e = 0; e < lm.num_edges(); ++e) {
    const int a = local_orig[lm.edge_vertex(e, 0)], b = local_orig[lm.edge_vertex(e, 1)];
    const int oe = m.find_edge(a, b);
    if (oe < 0) throw CannotCutOut{};
    out.level.edge_sharpness[e] = lm.is_boundary_edge(e) ? kInfSharp : L.edge_sharpness[oe];
  }
  return out;
}

/// One refinement step around face f: its 2-ring cut out and refined. `first_child` is the
/// child face of f's corner 0 (its corner k child is first_child + k). Where the 2-ring cannot
/// be cut out as a mesh of its own (two edges joining the same two vertices, as next to folded
/// valence-2 vertices) the whole level is refined instead.
LocalLevel refine_local(const SubdivLevel& L, const std::vector<Point3>& P, int f, int& first_child) {
  LocalLevel out;
  RefinementStep step;
  std::vector<Point3> src;
  try {
    LocalLevel sub = extract_two_ring(L, P, f);
    step = refine_once(sub.level);
    src = std::move(sub.pos);
    first_child = 0;
  } catch (const CannotCutOut&) {
    step = refine_once(L);
    src = P;
    first_child = L.mesh.face_begin(f);
  }
  step.stencils.apply(src, out.pos);
  out.level = std::move(step.child);
  return out;
}

}  // namespace

/// Refined neighbourhoods of the faces a descent passes through, keyed by the face it starts
/// from and the path of child corners. Queries that are close together (the samples of one
/// patch, the steps of a closest-point search) share their descents instead of refining the
/// same 2-rings again. Bounded: cleared when full. 8192 nodes: on catmark_rook's report 16384
/// took 125 MB more (575 against 450 MB peak) for no measurable gain; 4096 cost car-as-triangles'
/// report 15 % more time.
struct LimitEvaluator::DescentCache {
  struct Node {
    LocalLevel level;
    int first_child = 0;
    std::array<Prepared, 4> children;  ///< prepare() of the four child faces
  };
  std::mutex mutex;
  std::unordered_map<std::uint64_t, std::shared_ptr<const Node>> nodes;
  static constexpr size_t kMaxNodes = 8192;

  template <class Make>
  std::shared_ptr<const Node> get(std::uint64_t key, Make&& make) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      auto it = nodes.find(key);
      if (it != nodes.end()) return it->second;
    }
    auto node = std::make_shared<const Node>(make());
    std::lock_guard<std::mutex> lock(mutex);
    if (nodes.size() >= kMaxNodes) nodes.clear();
    nodes.emplace(key, node);
    return node;
  }
};

namespace {

/// The sample of a prepared face (not Refined) at local (s, t), with derivatives with respect to
/// the parameters A maps to (s, t). At an extraordinary vertex itself (eval_prepared's
/// `singular`): the exact position and normal (from the edge-ray tangents), curvature undefined.
LimitSample sample_prepared(const Prepared& pr, double s, double t, const Affine& A) {
  bool singular = false;
  const Derivs d = eval_prepared(pr, s, t, &singular);
  LimitSample out = to_ptex(d, pr.method == LimitMethod::Stam ? A.then(corner_frame(pr.corner)) : A);
  if (singular) {
    const Point3 n = {out.du[1] * out.dv[2] - out.du[2] * out.dv[1], out.du[2] * out.dv[0] - out.du[0] * out.dv[2],
                      out.du[0] * out.dv[1] - out.du[1] * out.dv[0]};
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int c = 0; c < 3; ++c) out.normal[c] = len > 0 ? n[c] / len : 0.0;
    out.duu = out.duv = out.dvv = Point3{};
    out.k1 = out.k2 = out.mean = out.gauss = std::numeric_limits<double>::quiet_NaN();
    out.exact_derivatives = false;
    return out;
  }
  finish_sample(out);
  if (pr.method == LimitMethod::Stam) stam_normal_fallback(pr, out);
  return out;
}

using DescentCache = LimitEvaluator::DescentCache;

/// The general driver: face f of level L, local face coordinates (s, t) = A (u, v) + c.
/// With a cache, `key` names face f0 of L0 uniquely among the evaluator's descents (0: none).
LimitSample eval_general(const SubdivLevel& L0, const std::vector<Point3>& P0, int f0, double s0,
                         double t0, Affine A, LimitMethod* method, int depth = 0,
                         DescentCache* cache = nullptr, std::uint64_t key = 0) {
  const SubdivLevel* L = &L0;
  const std::vector<Point3>* P = &P0;
  LocalLevel cur;
  std::shared_ptr<const DescentCache::Node> cached;
  int f = f0;
  double s = s0, t = t0;
  for (;; ++depth) {
    if (L->face_hole[f]) throw std::domain_error("limit: the point lies on a hole (no limit surface)");
    Prepared fresh;
    if (!cached) fresh = prepare(*L, *P, f);
    const Prepared& pr = cached ? cached->children[f - cached->first_child] : fresh;
    if (pr.method != LimitMethod::Refined) {
      if (method) *method = depth == 0 ? pr.method : LimitMethod::Refined;
      return sample_prepared(pr, s, t, A);
    }
    const PolyMesh& m = L->mesh;
    // Quad: which corner's child holds (s, t)? (n-gons only occur at the base, handled by the caller.)
    const int k = s < 0.5 ? (t < 0.5 ? 0 : 3) : (t < 0.5 ? 1 : 2);
    double a, b;
    corner_frame(k).apply(s, t, a, b);
    const bool at_corner = a <= 0 && b <= 0;
    // A corner stays irregular under refinement only if no semi-sharp tag is left to decay.
    const int corner_v = m.corner_vertex(m.face_begin(f) + k);
    if ((at_corner && classify_corner(*L, m.face_begin(f) + k) == CornerKind::Other &&
         no_semi_sharp_at(*L, corner_v)) ||
        depth >= kMaxDepth) {
      // At (or within 2^-kMaxDepth of) a corner that refinement never makes regular: the
      // documented fallback. Derivatives from the point 2^-40 inside the face along the corner's
      // diagonal (its descent ends after about 20 more levels), position exact.
      const Affine fr = corner_frame(k);  // orthogonal: (s, t) = R^T ((a, b) - c)
      Affine inv{fr.m00, fr.m10, fr.m01, fr.m11, 0, 0};
      double cx, cy;
      inv.apply(-fr.c0, -fr.c1, cx, cy);
      inv.c0 = cx;
      inv.c1 = cy;
      const double da = std::ldexp(1.0, -kNudgeExponent);
      double ns, nt;
      inv.apply(da, da, ns, nt);
      LimitSample out = eval_general(*L, *P, f, ns, nt, A, nullptr, 1);
      // Limit stencils of the face's 2-ring only (exact for its vertices: see extract_two_ring).
      LocalLevel ring;
      int v;
      try {
        ring = extract_two_ring(*L, *P, f);
        v = ring.level.mesh.corner_vertex(k);  // local face 0 keeps f's corner order
      } catch (const CannotCutOut&) {  // see refine_local
        ring.level = *L;
        ring.pos = *P;
        v = m.corner_vertex(m.face_begin(f) + k);
      }
      // Only v's own tags decide its limit (its rule, its crease neighbours); clearing the
      // others keeps limit_stencils on closed-form masks instead of refining past semi-sharp
      // tags elsewhere in the ring.
      {
        const PolyMesh& rm = ring.level.mesh;
        std::vector<char> at_v(rm.num_edges(), 0);
        for_each_vertex_edge(rm, v, [&](int e, int) { at_v[e] = 1; });
        for (int e = 0; e < rm.num_edges(); ++e)
          if (!at_v[e] && semi(ring.level.edge_sharpness[e])) ring.level.edge_sharpness[e] = 0.0f;
        for (int x = 0; x < rm.num_vertices(); ++x)
          if (x != v && semi(ring.level.vertex_sharpness[x])) ring.level.vertex_sharpness[x] = 0.0f;
      }
      const StencilTable lim = limit_stencils(ring.level);
      Point3 p{};
      for (int q = lim.offsets[v]; q < lim.offsets[v + 1]; ++q) axpy(p, lim.weights[q], ring.pos[lim.indices[q]]);
      out.p = p;
      out.exact_derivatives = false;
      if (method) *method = LimitMethod::Fallback;
      return out;
    }
    int first_child = 0;
    if (cache && key != 0 && key < (std::uint64_t{1} << 61)) {
      cached = cache->get(key, [&] {
        DescentCache::Node n;
        n.level = refine_local(*L, *P, f, n.first_child);
        for (int c = 0; c < 4; ++c) n.children[c] = prepare(n.level.level, n.level.pos, n.first_child + c, true);
        return n;
      });
      key = key * 4 + static_cast<std::uint64_t>(k);
      L = &cached->level.level;
      P = &cached->level.pos;
      first_child = cached->first_child;
    } else {
      LocalLevel next = refine_local(*L, *P, f, first_child);
      cur = std::move(next);
      L = &cur.level;
      P = &cur.pos;
      key = 0;
      cached = nullptr;
    }
    f = first_child + k;
    A = A.then(child_map(k));
    s = 2 * a;
    t = 2 * b;
  }
}

void finish_sample_local(LimitSample& o) { finish_sample(o); }

}  // namespace

LimitSample sample_from_derivatives(const SurfaceDerivs& d) {
  return finished_sample(d.p, d.du, d.dv, d.duu, d.duv, d.dvv);
}

void finish_sample(LimitSample& o) {
  const Point3& a = o.du;
  const Point3& b = o.dv;
  Point3 n = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  auto dot = [](const Point3& x, const Point3& y) { return x[0] * y[0] + x[1] * y[1] + x[2] * y[2]; };
  if (!(len > 0)) {
    o.normal = {0, 0, 0};
    o.k1 = o.k2 = o.mean = o.gauss = std::numeric_limits<double>::quiet_NaN();
    return;
  }
  const double inv_len = 1 / len;
  for (int c = 0; c < 3; ++c) o.normal[c] = n[c] * inv_len;
  const double E = dot(a, a), F = dot(a, b), G = dot(b, b);
  const double Ls = dot(o.duu, o.normal), Ms = dot(o.duv, o.normal), Ns = dot(o.dvv, o.normal);
  const double inv_det = 1 / (E * G - F * F);
  o.gauss = (Ls * Ns - Ms * Ms) * inv_det;
  o.mean = (E * Ns - 2 * F * Ms + G * Ls) * (0.5 * inv_det);
  const double disc = std::sqrt(std::max(0.0, o.mean * o.mean - o.gauss));
  o.k1 = o.mean + disc;
  o.k2 = o.mean - disc;
}

/// Per base face: its own preparation (regular / Stam), or, for a face that needs refining,
/// the preparations of its level-1 children and (if some child still needs refining, up to
/// kMaxStoredLevels faces) its refined 2-ring, so that no query repeats the first refinement.
struct LimitEvaluator::FaceCache {
  Prepared prepared;
  std::vector<Prepared> children;
  std::shared_ptr<const LocalLevel> level1;
  int first_child = 0;
};

namespace {
constexpr int kMaxStoredLevels = 4096;
}

LimitEvaluator::LimitEvaluator(SubdivLevel base, std::vector<Point3> positions)
    : base_(std::move(base)), positions_(std::move(positions)), descent_(std::make_unique<DescentCache>()) {
  const PolyMesh& m = base_.mesh;
  if (static_cast<int>(positions_.size()) != m.num_vertices())
    throw std::invalid_argument("LimitEvaluator: one position per vertex expected");
  face_ptex_.resize(m.num_faces());
  face_cache_.assign(m.num_faces(), -1);
  std::vector<int> cached;  // the faces with a cache entry, in face order
  for (int f = 0; f < m.num_faces(); ++f) {
    face_ptex_[f] = static_cast<int>(ptex_face_.size());
    const int size = m.face_size(f);
    for (int i = 0; i < (size == 4 ? 1 : size); ++i) ptex_face_.push_back(f);
    if (base_.face_hole[f]) continue;
    face_cache_[f] = static_cast<int>(cached.size());
    cached.push_back(f);
  }
  // Faces are prepared in parallel, a block at a time; the refined levels kept (at most
  // kMaxStoredLevels, the first in face order) are chosen after each block.
  cache_.resize(cached.size());
  constexpr int kBlock = 4096;
  int stored = 0;
  for (size_t first = 0; first < cached.size(); first += kBlock) {
    const int count = static_cast<int>(std::min<size_t>(kBlock, cached.size() - first));
    parallel_for(count, [&](int i) {
      const int f = cached[first + i];
      FaceCache& fc = cache_[first + i];
      const int size = m.face_size(f);
      if (size == 4) fc.prepared = prepare(base_, positions_, f, true);
      if (fc.prepared.method != LimitMethod::Refined) return;
      auto lvl = std::make_shared<LocalLevel>(refine_local(base_, positions_, f, fc.first_child));
      bool all = true;
      for (int k = 0; k < size; ++k) {
        fc.children.push_back(prepare(lvl->level, lvl->pos, fc.first_child + k, true));
        all = all && fc.children.back().method != LimitMethod::Refined;
      }
      if (!all) fc.level1 = std::move(lvl);
    });
    for (int i = 0; i < count; ++i) {
      FaceCache& fc = cache_[first + i];
      if (!fc.level1) continue;
      if (stored < kMaxStoredLevels) {
        ++stored;
      } else {
        fc.level1.reset();
      }
    }
  }
}

LimitEvaluator::~LimitEvaluator() = default;
LimitEvaluator::LimitEvaluator(LimitEvaluator&&) noexcept = default;

LimitSample LimitEvaluator::evaluate_ptex(int ptex, double u, double v, LimitMethod* method) const {
  if (ptex < 0 || ptex >= num_ptex_faces())
    throw std::out_of_range("no ptex face " + std::to_string(ptex) + " (the mesh has " +
                            std::to_string(num_ptex_faces()) + ")");
  const int f = ptex_face_[ptex];
  return evaluate(f, ptex - face_ptex_[f], u, v, method);
}

LimitPoint LimitEvaluator::evaluate_point(int f, int sub, double u, double v) const {
  if (f >= 0 && f < static_cast<int>(face_cache_.size()) && sub == 0 && u >= 0 && u <= 1 && v >= 0 &&
      v <= 1) {
    const int c = face_cache_[f];
    if (c >= 0 && on_grid(cache_[c].prepared)) {
      double Ns[4], Ds[4], DDs[4], Nt[4], Dt[4], DDt[4];
      grid_bases(cache_[c].prepared, u, v, Ns, Ds, DDs, Nt, Dt, DDt);
      LimitPoint d;
      bicubic_first(cache_[c].prepared.grid.data(), Ns, Ds, Nt, Dt, d.p, d.du, d.dv);
      return d;
    }
    if (c >= 0 && cache_[c].prepared.method == LimitMethod::Stam) {
      const Prepared& pr = cache_[c].prepared;
      bool singular = false;
      const Derivs d = eval_prepared(pr, u, v, &singular);
      if (!singular) {
        const LimitSample s = to_ptex(d, corner_frame(pr.corner));
        return LimitPoint{s.p, s.du, s.dv};
      }
    }
  }
  const LimitSample s = evaluate(f, sub, u, v);
  return LimitPoint{s.p, s.du, s.dv};
}

void LimitEvaluator::evaluate_grid(int f, int sub, const double* us, int nu, const double* vs, int nv,
                                   LimitSample* out) const {
  bool inside = true;
  for (int a = 0; a < nu; ++a) inside = inside && us[a] >= 0 && us[a] <= 1;
  for (int b = 0; b < nv; ++b) inside = inside && vs[b] >= 0 && vs[b] <= 1;
  const int c = f >= 0 && f < static_cast<int>(face_cache_.size()) ? face_cache_[f] : -1;
  const bool closed_form =
      c >= 0 && sub == 0 && inside && cache_[c].children.empty() && on_grid(cache_[c].prepared);
  if (!closed_form) {
    for (int a = 0; a < nu; ++a)
      for (int b = 0; b < nv; ++b) out[a * nv + b] = evaluate(f, sub, us[a], vs[b]);
    return;
  }
  // The bicubic sum contracted along s once per us[a] (rows R_k = sum_i N_s^(k)_i P_i.), then
  // along t per point.
  const Prepared& pr = cache_[c].prepared;
  thread_local std::vector<std::array<double, 12>> tb;  // per vs[b]: N, D, DD in t
  tb.resize(static_cast<size_t>(nv));
  for (int b = 0; b < nv; ++b) axis_basis(pr, 1, vs[b], &tb[b][0], &tb[b][4], &tb[b][8]);
  for (int a = 0; a < nu; ++a) {
    double N[3][4];
    axis_basis(pr, 0, us[a], N[0], N[1], N[2]);
    Point3 R[3][4] = {};
    for (int k = 0; k < 3; ++k)
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) axpy(R[k][j], N[k][i], pr.grid[4 * i + j]);
    for (int b = 0; b < nv; ++b) {
      const double* Nt = &tb[b][0];
      const double* Dt = &tb[b][4];
      const double* DDt = &tb[b][8];
      Derivs d;
      for (int j = 0; j < 4; ++j) {
        axpy(d.p, Nt[j], R[0][j]);
        axpy(d.ds, Nt[j], R[1][j]);
        axpy(d.dt, Dt[j], R[0][j]);
        axpy(d.dss, Nt[j], R[2][j]);
        axpy(d.dst, Dt[j], R[1][j]);
        axpy(d.dtt, DDt[j], R[0][j]);
      }
      // The ptex parameters are the face's own (to_ptex with the identity).
      out[a * nv + b] = finished_sample(d.p, d.ds, d.dt, d.dss, d.dst, d.dtt);
    }
  }
}

bool LimitEvaluator::is_polynomial(int f, int sub) const {
  if (f < 0 || f >= static_cast<int>(face_cache_.size()) || sub != 0 || base_.face_hole[f]) return false;
  const int c = face_cache_[f];
  return c >= 0 && cache_[c].children.empty() && cache_[c].prepared.method == LimitMethod::Regular;
}

LimitSample LimitEvaluator::evaluate(int f, int sub, double u, double v, LimitMethod* method) const {
  const PolyMesh& m = base_.mesh;
  if (f < 0 || f >= m.num_faces()) throw std::out_of_range("no face " + std::to_string(f));
  const int size = m.face_size(f);
  if (size == 4 ? sub != 0 : (sub < 0 || sub >= size))
    throw std::out_of_range("face " + std::to_string(f) + " has no sub-face " + std::to_string(sub));
  if (!(u >= 0 && u <= 1 && v >= 0 && v <= 1))
    throw std::out_of_range("parameters (" + std::to_string(u) + ", " + std::to_string(v) +
                            ") outside [0,1]^2");
  if (base_.face_hole[f]) throw std::domain_error("face " + std::to_string(f) + " is a hole (no limit surface)");
  const int cache_index = face_cache_[f];
  if (cache_index >= 0 && !cache_[cache_index].children.empty()) {
    const FaceCache& fc = cache_[cache_index];
    int k;
    double s, t;
    Affine A;
    if (size == 4) {
      k = u < 0.5 ? (v < 0.5 ? 0 : 3) : (v < 0.5 ? 1 : 2);
      A = child_map(k);
      A.apply(u, v, s, t);
    } else {
      k = sub;
      s = u;
      t = v;
    }
    const Prepared& cp = fc.children[k];
    if (cp.method != LimitMethod::Refined) {
      // Also at the child's extraordinary vertex: what the descent below would return (its first
      // level finds the same Stam corner), without refining the face's neighbourhood again per
      // point (around a 1000-gon that was O(n) per corner sample, O(n^2) per face ring).
      if (method) *method = LimitMethod::Refined;
      return sample_prepared(cp, s, t, A);
    }
    if (fc.level1) {
      // Key: a leading 1 bit, the cache slot, 10 bits for the child (an n-gon has n), then 2
      // bits per level of the path.
      const std::uint64_t key =
          ((std::uint64_t{1} << 24) + static_cast<std::uint64_t>(cache_index)) * 1024 + static_cast<std::uint64_t>(k);
      LimitSample out = eval_general(fc.level1->level, fc.level1->pos, fc.first_child + k, s, t, A, method, 1,
                                     descent_.get(), cache_index < (1 << 24) && k < 1024 ? key : 0);
      if (method && *method != LimitMethod::Fallback) *method = LimitMethod::Refined;
      return out;
    }
  }
  if (size == 4) {
    const int c = cache_index;
    if (c >= 0 && cache_[c].prepared.method != LimitMethod::Refined) {
      // Also at the extraordinary vertex: what eval_general would return after preparing the
      // face again (an O(n^2) product at a valence-n vertex, per point).
      if (method) *method = cache_[c].prepared.method;
      return sample_prepared(cache_[c].prepared, u, v, Affine{});
    }
    return eval_general(base_, positions_, f, u, v, Affine{}, method);
  }
  // n-gon: sub-face `sub` is the level-1 child quad at corner `sub` of the local copy.
  int first_child = 0;
  LocalLevel lvl = refine_local(base_, positions_, f, first_child);
  LimitSample out = eval_general(lvl.level, lvl.pos, first_child + sub, u, v, Affine{}, method, 1);
  if (method && *method != LimitMethod::Fallback) *method = LimitMethod::Refined;
  return out;
}

}  // namespace subd2nurbs
