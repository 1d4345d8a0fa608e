#include "core/fit/shape_fit.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cstdint>
#include <exception>
#include <cmath>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <thread>

#include "core/features/features.h"
#include "core/fit/fairing.h"
#include "core/fit/interpolate.h"
#include "core/fit/limit_rows.h"
#include "core/fit/sparse_util.h"
#include "core/limit/limit_evaluator.h"
#include "core/refine/quad_grid.h"
#include "core/util/error.h"
#include "core/util/gauss_newton.h"
#include "core/util/bicubic.h"
#include "core/util/constants.h"
#include "core/util/parallel.h"

namespace subd2nurbs {

using fit_detail::BlockLDLT3;
using fit_detail::SparseMatrix;

ShapeFitOptions exact_target_options() {
  ShapeFitOptions o;
  o.target_weight = 30;
  o.final_surface_weight = 1e-3;
  o.crease_angle = 30;
  o.smoothing = 0;
  o.max_iterations = 100;
  o.tolerance = 1e-8;
  return o;
}

const char* to_string(ShapeFitStop s) {
  switch (s) {
    case ShapeFitStop::Tolerance: return "tolerance";
    case ShapeFitStop::Converged: return "converged";
    case ShapeFitStop::IterationLimit: return "iteration limit";
    case ShapeFitStop::Cancelled: return "cancelled";
  }
  return "?";
}

namespace {

using Vec3 = Eigen::Vector3d;
Vec3 vec(const Point3& p) { return {p[0], p[1], p[2]}; }

/// The solver's samples: limit points of the level-k vertices that have a limit, as rows over
/// the cage, with the level-k mesh to estimate normals and spacing.
struct Samples {
  SubdivLevel level;              ///< level k
  StencilTable to_level;          ///< cage -> level-k vertices
  StencilTable limit;             ///< limit rows of every level-k vertex over level k
  StencilTable all_rows;          ///< the same over the cage
  std::vector<int> vertex;        ///< sample -> level-k vertex
  /// Per level-k face: index into `grids` where the face is a regular B-spline patch of 16
  /// level-k vertices (all four corners smooth, interior, valence 4, no tag on their edges), or -1.
  std::vector<int> grid_of;
  std::vector<std::array<int, 16>> grids;  ///< net index 4 i + j (i along u), -1..2 -> 0..3
  /// Per level-k face: where it lies in the cage's ptex parameters, (u, v) = o + s a + t b for
  /// its own (s, t) in [0, 1]^2 (refiner.h's child layout: child h at corner h, (0, 0) at the
  /// corner, s towards the midpoint of the corner's outgoing edge).
  struct PtexMap {
    int face = 0, sub = 0;
    double o[2] = {0, 0}, a[2] = {1, 0}, b[2] = {0, 1};
    void apply(double s, double t, double& u, double& v) const {
      u = o[0] + s * a[0] + t * b[0];
      v = o[1] + s * a[1] + t * b[1];
    }
  };
  std::vector<PtexMap> ptex;
};

/// The ptex maps of the faces of every level of `ref` down to `levels` (level-k faces).
std::vector<Samples::PtexMap> ptex_maps(const SubdivLevel& cage, const Refinement& ref, int levels) {
  std::vector<Samples::PtexMap> cur(cage.mesh.num_faces());
  for (int f = 0; f < cage.mesh.num_faces(); ++f) cur[f].face = f;
  for (int l = 0; l < levels; ++l) {
    const PolyMesh& parent = l == 0 ? cage.mesh : ref.levels[l].mesh;
    std::vector<Samples::PtexMap> next(ref.levels[l + 1].mesh.num_faces());
    for (int h = 0; h < static_cast<int>(next.size()); ++h) {
      const int F = parent.corner_face(h), i = h - parent.face_begin(F);
      const Samples::PtexMap& P = cur[F];
      Samples::PtexMap& c = next[h];
      c.face = P.face;
      c.sub = P.sub;
      if (parent.face_size(F) != 4) {  // an n-gon of the cage: child i is ptex sub-face i itself
        c.sub = i;
        continue;
      }
      // The child's (s, t) in the parent's (s, t): o + s a + t b.
      static const double co[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
      static const double ca[4][2] = {{0.5, 0}, {0, 0.5}, {-0.5, 0}, {0, -0.5}};
      static const double cb[4][2] = {{0, 0.5}, {-0.5, 0}, {0, -0.5}, {0.5, 0}};
      for (int d = 0; d < 2; ++d) {
        c.o[d] = P.o[d] + co[i][0] * P.a[d] + co[i][1] * P.b[d];
        c.a[d] = ca[i][0] * P.a[d] + ca[i][1] * P.b[d];
        c.b[d] = cb[i][0] * P.a[d] + cb[i][1] * P.b[d];
      }
    }
    cur = std::move(next);
  }
  return cur;
}

bool smooth_regular_corner(const SubdivLevel& L, int v) {
  const PolyMesh& m = L.mesh;
  if (m.is_boundary_vertex(v) || m.vertex_face_count(v) != 4 || L.vertex_sharpness[v] != 0.0f) return false;
  bool smooth = true;
  for_each_vertex_edge(m, v, [&](int e, int) { smooth = smooth && L.edge_sharpness[e] == 0.0f; });
  const int* c = m.vertex_corners(v);
  for (int i = 0; i < 4; ++i) smooth = smooth && m.face_size(m.corner_face(c[i])) == 4;
  return smooth;
}

Samples make_samples(const SubdivLevel& cage, int levels) {
  Samples s;
  Refinement ref = refine_uniform(cage, levels);
  s.to_level = ref.stencils_from_base(levels);
  s.ptex = ptex_maps(cage, ref, levels);
  s.level = std::move(ref.levels[levels]);
  const LimitRows lr = limit_rows(s.level);
  s.all_rows = lr.rows.compose(s.to_level);
  s.limit = lr.rows;
  const PolyMesh& m = s.level.mesh;
  const int nk = m.num_vertices();
  std::vector<char> none(nk, 0);
  for (int v : lr.no_surface) none[v] = 1;
  for (int v = 0; v < nk; ++v)
    if (!none[v]) s.vertex.push_back(v);
  s.grid_of.assign(m.num_faces(), -1);
  const std::vector<Point3> zero(nk, Point3{0, 0, 0});
  const bool diagonal[4] = {true, true, true, true};
  for (int f = 0; f < m.num_faces(); ++f) {
    if (s.level.face_hole[f] || m.face_size(f) != 4) continue;
    bool regular = true;
    for (int k = 0; k < 4 && regular; ++k) regular = smooth_regular_corner(s.level, m.face_vertices(f)[k]);
    if (!regular) continue;
    QuadGrid g;
    gather_quad_grid(s.level, zero, f, diagonal, g);
    std::array<int, 16> ids;
    for (int k = 0; k < 16 && regular; ++k) {
      regular = g.have[k] && g.vertex[k] >= 0;
      ids[k] = g.vertex[k];
    }
    if (!regular) continue;
    s.grid_of[f] = static_cast<int>(s.grids.size());
    s.grids.push_back(ids);
  }
  return s;
}

/// Unit normal of every level-k vertex from the limit positions X: the sum of the Newell normals
/// of the non-hole level-k faces around it.
void sample_normals(const SubdivLevel& L, const std::vector<Point3>& X, std::vector<Vec3>& normal) {
  const PolyMesh& m = L.mesh;
  normal.assign(m.num_vertices(), Vec3::Zero());
  for (int f = 0; f < m.num_faces(); ++f) {
    if (L.face_hole[f]) continue;
    const int* fv = m.face_vertices(f);
    const int n = m.face_size(f);
    Vec3 nf = Vec3::Zero();
    for (int i = 0; i < n; ++i) nf += vec(X[fv[i]]).cross(vec(X[fv[(i + 1) % n]]));
    for (int i = 0; i < n; ++i) normal[fv[i]] += nf;
  }
  for (Vec3& n : normal) {
    const double len = n.norm();
    if (len > 0) n /= len;
  }
}

/// Uniform cubic B-spline basis values and first derivatives on one span.
void bspline(double t, double b[4], double d[4]) {
  double dd[4];
  bspline_basis(t, b, d, dd);
}

/// The closest surface point found for one target point: a row over the level-k vertices
/// (B-spline: 16 entries; fallback triangle: up to 3 samples' limit rows).
struct Foot {
  double distance2 = std::numeric_limits<double>::infinity();
  Vec3 point = Vec3::Zero(), normal = Vec3::Zero();
  /// B-spline patch (index into Samples::grids), kExact: the exact limit on level-k face `face`
  /// at (u, v) of that face (LimitEvaluator, rows from ExactRows), or -1: triangle
  int grid = -1;
  int face = -1;
  double u = 0, v = 0;           ///< B-spline / level-k face parameters
  std::array<int, 3> tri{};      ///< triangle: level-k vertices
  std::array<double, 3> bary{};  ///< and barycentric weights
};

constexpr int kExact = -2;

/// Exact rows of limit points anywhere on the surface, also where the limit is not one bicubic
/// patch (extraordinary vertices, creases, boundaries): the limit is linear in the cage, so the
/// weight of cage vertex i at a point is the limit of the cage whose positions are the unit
/// vector e_i. The cage's vertices are coloured so that no two vertices of one face's 1-ring
/// (the support of its limit patch) share a colour; one evaluator per three colours carries the
/// indicator of one colour in each coordinate, and reads every support vertex's weight at once.
struct ExactRows {
  std::vector<int> colour;                    ///< per cage vertex
  std::vector<std::vector<int>> support;      ///< per cage face: its 1-ring's vertices
  std::vector<LimitEvaluator> basis;          ///< basis[c / 3], coordinate c % 3
  std::vector<std::vector<int>> bases;        ///< per cage face: the bases its support's colours are in

  explicit ExactRows(const SubdivLevel& cage) {
    const PolyMesh& m = cage.mesh;
    const int n = m.num_vertices(), nf = m.num_faces();
    support.resize(nf);
    std::vector<int> mark(n, -1);
    for (int f = 0; f < nf; ++f) {
      const int* fv = m.face_vertices(f);
      for (int k = 0; k < m.face_size(f); ++k) {
        const int* c = m.vertex_corners(fv[k]);
        for (int i = 0, nc = m.vertex_face_count(fv[k]); i < nc; ++i) {
          const int g = m.corner_face(c[i]);
          const int* gv = m.face_vertices(g);
          for (int j = 0; j < m.face_size(g); ++j)
            if (mark[gv[j]] != f) {
              mark[gv[j]] = f;
              support[f].push_back(gv[j]);
            }
        }
      }
    }
    // Greedy colouring: a vertex takes the smallest colour unused in every support it is in.
    std::vector<std::vector<int>> faces_of(n);
    for (int f = 0; f < nf; ++f)
      for (int v : support[f]) faces_of[v].push_back(f);
    colour.assign(n, -1);
    int colours = 0;
    std::vector<int> used;
    for (int v = 0; v < n; ++v) {
      used.clear();
      for (int f : faces_of[v])
        for (int w : support[f])
          if (colour[w] >= 0) used.push_back(colour[w]);
      std::sort(used.begin(), used.end());
      int c = 0;
      for (int u : used)
        if (u == c) ++c;
        else if (u > c) break;
      colour[v] = c;
      colours = std::max(colours, c + 1);
    }
    bases.resize(nf);
    for (int f = 0; f < nf; ++f) {
      for (int v : support[f]) bases[f].push_back(colour[v] / 3);
      std::sort(bases[f].begin(), bases[f].end());
      bases[f].erase(std::unique(bases[f].begin(), bases[f].end()), bases[f].end());
    }
    for (int e = 0; e < (colours + 2) / 3; ++e) {
      std::vector<Point3> pos(n, Point3{0, 0, 0});
      for (int v = 0; v < n; ++v)
        if (colour[v] / 3 == e) pos[v][colour[v] % 3] = 1.0;
      basis.emplace_back(cage, std::move(pos));
    }
  }
  /// The rows of two derivatives of the limit surface, (a1 d/du + b1 d/dv) and (a2 d/du + b2 d/dv),
  /// at (u, v) of ptex sub-face `sub` of `face`, over the face's support (idx = support[face]).
  void derivative_rows(int face, int sub, double u, double v, const double d1[2], const double d2[2],
                       std::vector<int>& idx, std::vector<double>& w1, std::vector<double>& w2) const {
    idx = support[face];
    w1.assign(idx.size(), 0.0);
    w2.assign(idx.size(), 0.0);
    std::vector<LimitPoint> value(basis.size());
    for (int e : bases[face]) value[e] = basis[e].evaluate_point(face, sub, u, v);
    for (std::size_t k = 0; k < idx.size(); ++k) {
      const LimitPoint& q = value[colour[idx[k]] / 3];
      const int c = colour[idx[k]] % 3;
      w1[k] = d1[0] * q.du[c] + d1[1] * q.dv[c];
      w2[k] = d2[0] * q.du[c] + d2[1] * q.dv[c];
    }
  }
  /// The row (cage vertices, weights) of the limit point at (u, v) of ptex sub-face `sub` of `face`.
  void row(int face, int sub, double u, double v, std::vector<int>& idx, std::vector<double>& w) const {
    idx.clear();
    w.clear();
    std::vector<LimitPoint> value(basis.size());
    for (int e : bases[face]) value[e] = basis[e].evaluate_point(face, sub, u, v);
    for (int vtx : support[face]) {
      const double x = value[colour[vtx] / 3].p[colour[vtx] % 3];
      if (x == 0) continue;
      idx.push_back(vtx);
      w.push_back(x);
    }
  }
};

/// Gauss-Newton projection of t onto the exact limit on level-k face f (its own (s, t),
/// evaluated by E in the cage's ptex parameters), started at (s, t), clamped to the face.
void project_exact(const Samples& S, const LimitEvaluator& E, int f, const Vec3& t, double s0, double t0, Foot& best) {
  const Samples::PtexMap& M = S.ptex[f];
  double s = s0, r = t0;
  LimitPoint q;
  Vec3 ds, dr;
  auto eval = [&]() {
    double u, v;
    M.apply(s, r, u, v);
    q = E.evaluate_point(M.face, M.sub, std::clamp(u, 0.0, 1.0), std::clamp(v, 0.0, 1.0));
    ds = M.a[0] * vec(q.du) + M.a[1] * vec(q.dv);
    dr = M.b[0] * vec(q.du) + M.b[1] * vec(q.dv);
  };
  eval();
  for (int iter = 0; iter < 10; ++iter) {
    const auto next = closest_point_step(vec(q.p) - t, ds, dr, s, r);
    if (!next) break;
    const auto [ns, nr] = *next;
    const bool done = std::abs(ns - s) + std::abs(nr - r) < 1e-15;
    s = ns;
    r = nr;
    eval();
    if (done) break;
  }
  const double d2 = (vec(q.p) - t).squaredNorm();
  if (d2 >= best.distance2) return;
  best.distance2 = d2;
  best.point = vec(q.p);
  const Vec3 nrm = ds.cross(dr);
  if (nrm.norm() > 0) best.normal = nrm.normalized();
  best.grid = kExact;
  best.face = f;
  best.u = s;
  best.v = r;
}

/// Gauss-Newton projection of t onto regular level-k patch `grid` (net from level-k positions Y),
/// started at (u, v), clamped to the patch.
void project_to_patch(const Samples& S, int grid, const std::vector<Point3>& Y, const Vec3& t, double u, double v,
                      Foot& best) {
  Point3 net[16];
  for (int k = 0; k < 16; ++k) net[k] = Y[S.grids[grid][k]];
  Point3 p, du, dv;
  for (int iter = 0;; ++iter) {
    double bu[4], dbu[4], bv[4], dbv[4];
    bspline(u, bu, dbu);
    bspline(v, bv, dbv);
    bicubic_first(net, bu, dbu, bv, dbv, p, du, dv);
    if (iter == 8) break;
    const auto next = closest_point_step(vec(p) - t, vec(du), vec(dv), u, v);
    if (!next) break;
    const auto [nu, nv] = *next;
    const bool done = std::abs(nu - u) + std::abs(nv - v) < 1e-15;
    u = nu;
    v = nv;
    if (done) {
      bspline(u, bu, dbu);
      bspline(v, bv, dbv);
      bicubic_first(net, bu, dbu, bv, dbv, p, du, dv);
      break;
    }
  }
  const double d2 = (vec(p) - t).squaredNorm();
  if (d2 >= best.distance2) return;
  best.distance2 = d2;
  best.point = vec(p);
  best.normal = vec(du).cross(vec(dv)).normalized();
  best.grid = grid;
  best.u = u;
  best.v = v;
}

/// The closest point to t on the surface pieces around level-k vertex `near` (its nearest
/// sample): the faces at `near` and at its edge neighbours (a foot need not lie in a face at the
/// nearest vertex where faces are long and thin); exact on regular patches (Gauss-Newton from
/// each face corner at `near` or its neighbour), else on the two triangles of limit points of
/// each face.
Foot foot_point(const Samples& S, const std::vector<Point3>& Y, const std::vector<Point3>& X,
                const std::vector<Vec3>& normal, const LimitEvaluator* E, const Vec3& t, int near) {
  static const double corner_uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  const PolyMesh& m = S.level.mesh;
  Foot best;
  int done[64];
  int ndone = 0;
  auto visit = [&](int v) {
    const int* c = m.vertex_corners(v);
    for (int i = 0, nf = m.vertex_face_count(v); i < nf; ++i) {
      const int f = m.corner_face(c[i]);
      if (S.level.face_hole[f] || std::find(done, done + ndone, f) != done + ndone) continue;
      if (ndone < 64) done[ndone++] = f;
      if (S.grid_of[f] >= 0) {
        const int k = c[i] - m.face_begin(f);
        project_to_patch(S, S.grid_of[f], Y, t, corner_uv[k][0], corner_uv[k][1], best);
        continue;
      }
      const int* fv = m.face_vertices(f);
      if (E && m.face_size(f) == 4) {  // exact: Newton from the nearer triangle's closest point
        static const double cs[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
        double s0 = 0, t0 = 0, near2 = std::numeric_limits<double>::infinity();
        for (int a = 1; a <= 2; ++a) {
          const Point3 q = closest_point_on_triangle({t[0], t[1], t[2]}, X[fv[0]], X[fv[a]], X[fv[a + 1]]);
          const double d2 = (vec(q) - t).squaredNorm();
          if (d2 >= near2) continue;
          near2 = d2;
          const std::array<double, 3> w = barycentric(q, X[fv[0]], X[fv[a]], X[fv[a + 1]]);
          s0 = w[0] * cs[0][0] + w[1] * cs[a][0] + w[2] * cs[a + 1][0];
          t0 = w[0] * cs[0][1] + w[1] * cs[a][1] + w[2] * cs[a + 1][1];
        }
        project_exact(S, *E, f, t, s0, t0, best);
        continue;
      }
      for (int a = 1; a + 1 < m.face_size(f); ++a) {
        const std::array<int, 3> tri = {fv[0], fv[a], fv[a + 1]};
        const Point3 q = closest_point_on_triangle({t[0], t[1], t[2]}, X[tri[0]], X[tri[1]], X[tri[2]]);
        const double d2 = (vec(q) - t).squaredNorm();
        if (d2 >= best.distance2) continue;
        best.distance2 = d2;
        best.point = vec(q);
        best.grid = -1;
        best.tri = tri;
        best.bary = barycentric(q, X[tri[0]], X[tri[1]], X[tri[2]]);
        best.normal =
            (best.bary[0] * normal[tri[0]] + best.bary[1] * normal[tri[1]] + best.bary[2] * normal[tri[2]]).normalized();
      }
    }
  };
  visit(near);
  const bool inside = best.grid != -1 ? best.u > 0 && best.u < 1 && best.v > 0 && best.v < 1
                                      : best.bary[0] > 0 && best.bary[1] > 0 && best.bary[2] > 0;
  if (!inside) for_each_vertex_edge(m, near, [&](int, int w) { visit(w); });
  return best;
}

int ptex_faces(const SubdivLevel& cage) {
  int count = 0;
  for (int f = 0; f < cage.mesh.num_faces(); ++f)
    if (!cage.face_hole[f]) count += cage.mesh.face_size(f) == 4 ? 1 : cage.mesh.face_size(f);
  return std::max(count, 1);
}

/// The normal equations in the cage's 3n coordinates, accumulated one weighted row at a time:
/// a row r over the cage (indices, weights) with the symmetric 3 x 3 weight W and g = W c adds
/// r^T r (x) W to the matrix and r^T g to the right-hand side. The matrix is kept as 3 x 3 blocks
/// of the vertex pairs (a <= b) that share a row, found through an open-addressing hash table:
/// memory and time grow with the pairs (about 50 per vertex), not with n^2.
///
/// The object lives through the whole fit: its blocks are zeroed between solves, not dropped,
/// so the sparse matrix keeps one structure (the pairs seeded at the start, every pair of one
/// cage face's support, and any pair a row adds later), whose fill-reducing ordering and
/// symbolic factorisation are computed once and only redone when a new pair appears.
struct NormalEquations {
  int n = 0;
  std::vector<std::uint64_t> keys;   ///< table slots: a n + b + 1, 0 for an empty slot
  std::vector<int> slot_block;       ///< table slot -> block index
  std::vector<int> block_a, block_b; ///< per block: its vertex pair
  std::vector<double> blocks;        ///< 9 per block, row-major
  Eigen::VectorXd rhs;               ///< coordinate-major: x of every vertex, then y, then z
  /// The factorised structure: the blocks' pattern (every pair of vertices with a block, and
  /// every pair lambda K couples), its fill-reducing ordering and symbolic factorisation
  /// (fit_detail::BlockLDLT3), and lambda K(a, b) for each block (the regulariser, constant).
  std::size_t structured_blocks = 0;
  std::vector<double> kvalue, values;
  BlockLDLT3 ldlt;
  std::vector<double> b3, x3;

  explicit NormalEquations(int vertices) : n(vertices), rhs(Eigen::VectorXd::Zero(3 * n)) {
    std::size_t capacity = 1024;
    while (capacity < static_cast<std::size_t>(n) * 128) capacity *= 2;
    keys.assign(capacity, 0);
    slot_block.assign(capacity, -1);
  }
  void reset() {
    std::fill(blocks.begin(), blocks.end(), 0.0);
    rhs.setZero();
  }
  /// The index of block (a, b), a <= b, created zero on first use.
  int block_index(int a, int b) {
    const std::uint64_t key = static_cast<std::uint64_t>(a) * static_cast<std::uint64_t>(n) + static_cast<std::uint64_t>(b) + 1;
    std::size_t mask = keys.size() - 1, i = static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> 20) & mask;
    while (keys[i] != 0 && keys[i] != key) i = (i + 1) & mask;
    if (keys[i] == 0) {
      if (2 * (block_a.size() + 1) > keys.size()) {  // keep the load at most 1/2
        grow();
        return block_index(a, b);
      }
      keys[i] = key;
      slot_block[i] = static_cast<int>(block_a.size());
      block_a.push_back(a);
      block_b.push_back(b);
      blocks.resize(blocks.size() + 9, 0.0);
    }
    return slot_block[i];
  }
  double* block(int a, int b) { return &blocks[static_cast<std::size_t>(9) * static_cast<std::size_t>(block_index(a, b))]; }
  void grow() {
    std::vector<std::uint64_t> old_keys(keys.size() * 2, 0);
    std::vector<int> old_slots(keys.size() * 2, -1);
    keys.swap(old_keys);
    slot_block.swap(old_slots);
    const std::size_t mask = keys.size() - 1;
    for (std::size_t k = 0; k < old_keys.size(); ++k) {
      if (old_keys[k] == 0) continue;
      std::size_t i = static_cast<std::size_t>((old_keys[k] * 0x9E3779B97F4A7C15ull) >> 20) & mask;
      while (keys[i] != 0) i = (i + 1) & mask;
      keys[i] = old_keys[k];
      slot_block[i] = old_slots[k];
    }
  }
  /// Only the blocks (a, b) with a <= b are accumulated (the matrix is symmetric, and so is W).
  void add(const int* idx, const double* w, int count, const Eigen::Matrix3d& W, const Vec3& g) {
    double w9[9];
    for (int k = 0; k < 9; ++k) w9[k] = W(k / 3, k % 3);
    for (int a = 0; a < count; ++a) {
      for (int c = 0; c < 3; ++c) rhs[c * n + idx[a]] += w[a] * g[c];
      for (int b = 0; b < count; ++b) {
        if (idx[b] < idx[a]) continue;
        const double s = w[a] * w[b];
        double* blk = block(idx[a], idx[b]);
        for (int k = 0; k < 9; ++k) blk[k] += s * w9[k];
      }
    }
  }
  /// The structure (every block, lambda K's pairs, the diagonal) and its symbolic
  /// factorisation, when blocks were added since the last one.
  void structure(const SparseMatrix* K, double lambda) {
    if (structured_blocks == block_a.size() && ldlt.size() == n) return;
    for (int v = 0; v < n; ++v) block_index(v, v);
    if (K)
      for (int col = 0; col < n; ++col)
        for (SparseMatrix::InnerIterator e(*K, col); e; ++e)
          if (e.row() <= col) block_index(static_cast<int>(e.row()), col);
    kvalue.assign(block_a.size(), 0.0);
    if (K)
      for (int col = 0; col < n; ++col)
        for (SparseMatrix::InnerIterator e(*K, col); e; ++e)
          if (e.row() <= col) kvalue[static_cast<std::size_t>(block_index(static_cast<int>(e.row()), col))] += lambda * e.value();
    structured_blocks = block_a.size();
    ldlt.analyze(n, block_a, block_b);
  }
  /// Solves (sum of the rows + lambda K (x) I3 + mu I) x = rhs + extra. \throw FitError
  Eigen::VectorXd solve(const SparseMatrix* K, double lambda, double mu, const Eigen::VectorXd& extra) {
    structure(K, lambda);
    values.assign(blocks.begin(), blocks.end());
    for (std::size_t i = 0; i < block_a.size(); ++i) {
      const double d = kvalue[i] + (block_a[i] == block_b[i] ? mu : 0.0);
      for (int k : {0, 4, 8}) values[9 * i + static_cast<std::size_t>(k)] += d;
    }
    if (!ldlt.factorize(values.data())) throw FitError("fit_to_shape: the normal equations could not be factorised", {});
    b3.resize(3 * static_cast<std::size_t>(n));
    x3.resize(3 * static_cast<std::size_t>(n));
    for (int c = 0; c < 3; ++c)
      for (int v = 0; v < n; ++v) b3[3 * static_cast<std::size_t>(v) + c] = rhs[c * n + v] + extra[c * n + v];
    ldlt.solve(b3.data(), x3.data());
    Eigen::VectorXd x(3 * n);
    for (int c = 0; c < 3; ++c)
      for (int v = 0; v < n; ++v) x[c * n + v] = x3[3 * static_cast<std::size_t>(v) + c];
    return x;
  }
  double trace() const {
    double t = 0;
    for (std::size_t i = 0; i < block_a.size(); ++i)
      if (block_a[i] == block_b[i])
        for (int k : {0, 4, 8}) t += blocks[9 * i + k];
    return t;
  }
};

/// Sums of scaled stencil rows, merged by source (a dense accumulator and the touched list).
struct RowSum {
  std::vector<double> acc;
  std::vector<int> idx;
  std::vector<double> w;
  explicit RowSum(int sources) : acc(sources, 0.0) {}
  void add(const StencilTable& t, int r, double s) {
    for (int k = t.offsets[r]; k < t.offsets[r + 1]; ++k) {
      if (acc[t.indices[k]] == 0) idx.push_back(t.indices[k]);
      acc[t.indices[k]] += s * t.weights[k];
      if (acc[t.indices[k]] == 0) acc[t.indices[k]] = 1e-300;  // stays listed
    }
  }
  void add(const std::vector<int>& i, const std::vector<double>& x) {
    for (size_t k = 0; k < i.size(); ++k) {
      if (acc[i[k]] == 0) idx.push_back(i[k]);
      acc[i[k]] += x[k];
      if (acc[i[k]] == 0) acc[i[k]] = 1e-300;
    }
  }
  void finish() {
    w.resize(idx.size());
    for (size_t k = 0; k < idx.size(); ++k) {
      w[k] = acc[idx[k]];
      acc[idx[k]] = 0;
    }
  }
  void clear() { idx.clear(); }
};

}  // namespace

StencilTable shape_fit_sample_rows(const SubdivLevel& cage, int levels) {
  if (levels < 1 || levels > 5) throw std::invalid_argument("shape_fit_sample_rows: levels must be 1..5");
  const Samples s = make_samples(cage, levels);
  StencilTable out;
  out.num_sources = cage.mesh.num_vertices();
  for (int v : s.vertex) {
    for (int k = s.all_rows.offsets[v]; k < s.all_rows.offsets[v + 1]; ++k) {
      out.indices.push_back(s.all_rows.indices[k]);
      out.weights.push_back(s.all_rows.weights[k]);
    }
    out.offsets.push_back(static_cast<int>(out.indices.size()));
  }
  return out;
}

namespace {

/// The surface samples' rows grouped by cage face: every sample whose row lies in one cage
/// face's support (all of them, in practice) is a row of that face's dense matrix R over the
/// support. A solve adds R^T diag(w) R for each of the six entries of the samples' 3 x 3
/// weights (one small dense product per face, faces in parallel), then scatters the sums into
/// the normal equations' blocks in face order: the same sums whatever the thread count.
struct SampleGroups {
  struct Group {
    std::vector<int> vertices;   ///< the face's support (cage vertices)
    std::vector<int> samples;    ///< its samples
    Eigen::MatrixXd R;           ///< samples x vertices: the rows
    std::vector<int> slot;       ///< m x m: block index of (vertices[a], vertices[b]) when a's <= b's, else -1
  };
  std::vector<Group> groups;
  std::vector<int> loose;        ///< samples in no group (accumulated one by one)

  SampleGroups(const SubdivLevel& cage, const Samples& S, const ExactRows& exact, NormalEquations& eq) {
    const PolyMesh& m = S.level.mesh;
    const int n = cage.mesh.num_vertices(), ns = static_cast<int>(S.vertex.size());
    std::vector<std::vector<int>> bucket(cage.mesh.num_faces());
    for (int i = 0; i < ns; ++i) {
      const int v = S.vertex[i];
      int face = -1;
      const int* c = m.vertex_corners(v);
      for (int k = 0, nc = m.vertex_face_count(v); k < nc && face < 0; ++k)
        if (!S.level.face_hole[m.corner_face(c[k])]) face = S.ptex[m.corner_face(c[k])].face;
      if (face < 0) loose.push_back(i);
      else bucket[face].push_back(i);
    }
    std::vector<int> local(n, -1);
    for (int f = 0; f < cage.mesh.num_faces(); ++f) {
      if (bucket[f].empty()) continue;
      Group g;
      g.vertices = exact.support[f];
      const int sz = static_cast<int>(g.vertices.size());
      for (int a = 0; a < sz; ++a) local[g.vertices[a]] = a;
      std::vector<int> in;
      for (int i : bucket[f]) {
        const int v = S.vertex[i];
        bool inside = true;
        for (int k = S.all_rows.offsets[v]; k < S.all_rows.offsets[v + 1] && inside; ++k)
          inside = local[S.all_rows.indices[k]] >= 0;
        (inside ? in : loose).push_back(i);
      }
      if (!in.empty()) {
        g.samples = in;
        g.R = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(in.size()), sz);
        for (std::size_t r = 0; r < in.size(); ++r) {
          const int v = S.vertex[in[r]];
          for (int k = S.all_rows.offsets[v]; k < S.all_rows.offsets[v + 1]; ++k)
            g.R(static_cast<Eigen::Index>(r), local[S.all_rows.indices[k]]) += S.all_rows.weights[k];
        }
        g.slot.assign(static_cast<std::size_t>(sz) * sz, -1);
        for (int a = 0; a < sz; ++a)
          for (int b = 0; b < sz; ++b)
            if (g.vertices[a] <= g.vertices[b]) g.slot[a * sz + b] = eq.block_index(g.vertices[a], g.vertices[b]);
      }
      for (int a = 0; a < sz; ++a) local[g.vertices[a]] = -1;
      if (!g.samples.empty()) groups.push_back(std::move(g));
    }
    std::sort(loose.begin(), loose.end());
  }

  /// Adds the samples' rows with weights Ma (xx, yy, zz, xy, xz, yz per sample) and W c = Ga.
  void accumulate(const Eigen::MatrixXd& Ma, const Eigen::MatrixXd& Ga, NormalEquations& eq) const {
    const int ng = static_cast<int>(groups.size());
    std::vector<Eigen::MatrixXd> gram(ng), right(ng);
    parallel_for(ng, [&](int gi) {
      const Group& g = groups[gi];
      const Eigen::Index rows = g.R.rows(), m = g.R.cols();
      Eigen::MatrixXd weighted(rows, 6 * m), gc(rows, 3);
      for (Eigen::Index r = 0; r < rows; ++r) {
        const int i = g.samples[static_cast<std::size_t>(r)];
        for (int c = 0; c < 6; ++c) weighted.block(r, c * m, 1, m) = Ma(i, c) * g.R.row(r);
        gc.row(r) = Ga.row(i);
      }
      gram[gi].noalias() = g.R.transpose() * weighted;
      right[gi].noalias() = g.R.transpose() * gc;
    });
    static const int comp[9] = {0, 3, 4, 3, 1, 5, 4, 5, 2};
    for (int gi = 0; gi < ng; ++gi) {
      const Group& g = groups[gi];
      const int m = static_cast<int>(g.vertices.size());
      const Eigen::MatrixXd& G = gram[gi];
      for (int a = 0; a < m; ++a) {
        for (int c = 0; c < 3; ++c) eq.rhs[c * eq.n + g.vertices[a]] += right[gi](a, c);
        for (int b = 0; b < m; ++b) {
          const int slot = g.slot[a * m + b];
          if (slot < 0) continue;
          double* blk = &eq.blocks[static_cast<std::size_t>(9) * static_cast<std::size_t>(slot)];
          for (int k = 0; k < 9; ++k) blk[k] += G(a, comp[k] * m + b);
        }
      }
    }
  }
};

/// A crease side's normal (ShapeFitOptions::crease_normal_weight): at the middle of a level-k
/// crease edge, on one side, the rows of the surface's derivatives along the crease (T) and
/// across it (D, along the level-k edge leaving it), over the cage face's support; the inward
/// point (ptex) where the target's normal n is taken. The surface's normal there is T x D; with
/// the frame (t, e, n) (t = T / |T|, e in the target's plane across t), T = |T| (t + alpha n)
/// and D = a t + b e + beta n, it is n + ((a alpha - beta) / b) e - alpha t to first order: two
/// residuals linear in the positions (a, b, |T| frozen at the iteration's positions), scaled by
/// |D| to lengths. 1 / b is why the positions alone do not hold the normal in a wedge-shaped
/// quad (D nearly along T: fandisk's fan tip, 17 deg between them, 3.4 x the tilt of D).
struct CreaseNormal {
  std::vector<int> idx;
  std::vector<double> wT, wD;
  int face = 0, sub = 0;
  double qu = 0, qv = 0;
  int hint = -1;
  struct State {
    Vec3 normal = Vec3::Zero();
    double weight = 0;                 ///< 0: not used in this iteration (the guard failed)
    std::vector<double> across, along; ///< the two residual rows (times n)
  } state;
};

/// One solve of a fit iteration: the cage positions minimising the weighted pairings (rows of A:
/// samples -> targets, weights Ma, W c Ga; rows of B: data points -> their feet, Mb, Gb) plus the
/// regulariser lambda K and the proximal term mu |P - P_prev|^2. \throw FitError
/// Returns the weight of the held vertices' planes in this solve (ShapeFitOptions::vertex_planes).
double solve_step(const Samples& S, const ExactRows* exact, const std::vector<Foot>& foot, const Eigen::MatrixXd& Ma, const Eigen::MatrixXd& Ga,
                const Eigen::MatrixXd& Mb, const Eigen::MatrixXd& Gb, const SparseMatrix& K, double lambda,
                double proximal, const SampleGroups& groups, const ShapeFitOptions& options,
                const std::vector<CreaseNormal>& crease_normals, NormalEquations& eq, std::vector<Point3>& P) {
  const int n = static_cast<int>(P.size()), nb = static_cast<int>(foot.size());
  // Solve (H + lambda K (x) I3 + mu I) P = rhs + mu P_prev, H = sum over the rows (samples,
  // then data points; each over the cage) of r^T r (x) W.
  eq.reset();
  auto weight = [](const Eigen::MatrixXd& M, int i) {
    Eigen::Matrix3d W;
    W << M(i, 0), M(i, 3), M(i, 4), M(i, 3), M(i, 1), M(i, 5), M(i, 4), M(i, 5), M(i, 2);
    return W;
  };
  groups.accumulate(Ma, Ga, eq);
  for (int i : groups.loose) {
    const int v = S.vertex[i], o = S.all_rows.offsets[v];
    eq.add(&S.all_rows.indices[o], &S.all_rows.weights[o], S.all_rows.row_size(v), weight(Ma, i), Ga.row(i).transpose());
  }
  // The exact limit rows of the feet that need them, evaluated in parallel (each is pure), then
  // summed in the feet's order as before.
  std::vector<int> exact_feet;
  for (int j = 0; j < nb; ++j)
    if (foot[j].grid == kExact) exact_feet.push_back(j);
  std::vector<std::vector<int>> ei(exact_feet.size());
  std::vector<std::vector<double>> ew(exact_feet.size());
  parallel_for(static_cast<int>(exact_feet.size()), [&](int k) {
    const Foot& f = foot[static_cast<std::size_t>(exact_feet[static_cast<std::size_t>(k)])];
    const Samples::PtexMap& M = S.ptex[f.face];
    double u, v;
    M.apply(f.u, f.v, u, v);
    exact->row(M.face, M.sub, std::clamp(u, 0.0, 1.0), std::clamp(v, 0.0, 1.0), ei[static_cast<std::size_t>(k)],
               ew[static_cast<std::size_t>(k)]);
  });
  RowSum row(n);
  std::size_t next_exact = 0;
  for (int j = 0; j < nb; ++j) {
    const Foot& f = foot[j];
    row.clear();
    if (f.grid == kExact) {
      row.add(ei[next_exact], ew[next_exact]);
      ++next_exact;
    } else if (f.grid >= 0) {
      double bu[4], dbu[4], bv[4], dbv[4];
      bspline(f.u, bu, dbu);
      bspline(f.v, bv, dbv);
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) row.add(S.to_level, S.grids[f.grid][4 * a + b], bu[a] * bv[b]);
    } else {
      for (int k = 0; k < 3; ++k) row.add(S.all_rows, f.tri[k], f.bary[k]);
    }
    row.finish();
    eq.add(row.idx.data(), row.w.data(), static_cast<int>(row.idx.size()), weight(Mb, j), Gb.row(j).transpose());
  }
  for (const CreaseNormal& c : crease_normals)
    if (c.state.weight > 0) {
      const Eigen::Matrix3d W = c.state.weight * c.state.normal * c.state.normal.transpose();
      const int count = static_cast<int>(c.idx.size());
      eq.add(c.idx.data(), c.state.across.data(), count, W, Vec3::Zero());
      eq.add(c.idx.data(), c.state.along.data(), count, W, Vec3::Zero());
    }
  const double mean_diagonal = eq.trace() / (3.0 * n);
  const double mu = proximal * mean_diagonal + 1e-300;
  const double plane_w = options.plane_weight * mean_diagonal;
  for (const ShapeFitOptions::VertexPlane& c : options.vertex_planes) {
    const Vec3 nv(c.normal[0], c.normal[1], c.normal[2]);
    const double one = 1;
    eq.add(&c.vertex, &one, 1, plane_w * nv * nv.transpose(), plane_w * c.offset * nv);
  }
  Eigen::VectorXd prox(3 * n);
  for (int c = 0; c < 3; ++c)
    for (int v = 0; v < n; ++v) prox[c * n + v] = mu * P[v][c];
  const Eigen::VectorXd x = eq.solve(lambda > 0 ? &K : nullptr, lambda, mu, prox);
  if (!x.allFinite()) throw FitError("fit_to_shape: the solve gave non-finite positions", {});
  for (int v = 0; v < n; ++v) P[v] = {x[v], x[n + v], x[2 * n + v]};
  return plane_w;
}


/// The surface's border: level-k halfedges of non-hole faces with no twin or a hole across.
struct Border {
  std::vector<std::pair<int, int>> edges;       ///< (face, corner index in the face 0..3)
  std::vector<std::vector<int>> at;             ///< level-k vertex -> indices into edges
  std::vector<int> vertices;                    ///< level-k vertices on the border
};

/// The surface's border (creases false), or its crease curves (creases true: the interior
/// level-k edges still sharp at level k, between two non-hole faces; each edge once).
Border surface_border(const SubdivLevel& L, bool creases = false) {
  const PolyMesh& m = L.mesh;
  Border b;
  b.at.resize(m.num_vertices());
  for (int f = 0; f < m.num_faces(); ++f) {
    if (L.face_hole[f] || m.face_size(f) != 4) continue;
    for (int k = 0; k < 4; ++k) {
      const int h = m.face_begin(f) + k, tw = m.twin(h);
      const bool open = tw < 0 || L.face_hole[m.corner_face(tw)];
      if (creases ? open || tw < h || !(L.edge_sharpness[m.corner_edge(h)] > 0) : !open) continue;
      const int e = static_cast<int>(b.edges.size());
      b.edges.push_back({f, k});
      for (int v : {m.face_vertices(f)[k], m.face_vertices(f)[(k + 1) % 4]}) {
        if (b.at[v].empty()) b.vertices.push_back(v);
        b.at[v].push_back(e);
      }
    }
  }
  return b;
}

/// The target's boundary vertices (on an edge of one triangle).
std::vector<int> target_border(const ShapeTarget& target) {
  std::map<std::pair<int, int>, int> count;
  for (const auto& t : target.triangles())
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      ++count[{std::min(a, b), std::max(a, b)}];
    }
  std::vector<char> on(target.points().size(), 0);
  for (const auto& [e, c] : count)
    if (c == 1) on[e.first] = on[e.second] = 1;
  std::vector<int> out;
  for (size_t v = 0; v < on.size(); ++v)
    if (on[v]) out.push_back(static_cast<int>(v));
  return out;
}

/// The sharp features of a triangle target (detect_features at `angle_degrees`); none for a
/// non-manifold target (its features are not defined).
FeatureSet target_features(const ShapeTarget& target, double angle_degrees) {
  MeshInput mi;
  mi.positions = target.points();
  for (const auto& t : target.triangles()) {
    mi.face_sizes.push_back(3);
    for (int v : t) mi.face_indices.push_back(v);
  }
  FeatureOptions fo;
  fo.angle_degrees = angle_degrees;
  try {
    return detect_features(mi, fo);
  } catch (const Error&) {
    return {};
  }
}

/// The target's feature vertices: ends of its sharp interior edges (detect_features, dihedral
/// angle; boundary edges left out: the border term holds them). None for a non-manifold target.
std::vector<int> target_creases(const ShapeTarget& target, double angle_degrees) {
  const FeatureSet fs = target_features(target, angle_degrees);
  std::map<std::pair<int, int>, int> count;
  for (const auto& t : target.triangles())
    for (int k = 0; k < 3; ++k) ++count[{std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3])}];
  std::vector<char> on(target.points().size(), 0);
  for (const auto& e : fs.edges)
    if (count[{e[0], e[1]}] == 2) on[e[0]] = on[e[1]] = 1;
  std::vector<int> out;
  for (size_t v = 0; v < on.size(); ++v)
    if (on[v]) out.push_back(static_cast<int>(v));
  return out;
}

/// The closest point to t on the surface's border curve near border vertex `near` (the border
/// edges at it and at their other ends), exact: 1-D Newton along each level-k border edge on the
/// exact limit. normal = the curve's unit tangent there.
Foot border_foot(const Samples& S, const Border& B, const LimitEvaluator& E, const std::vector<Point3>& X, const Vec3& t,
                 int near) {
  static const double co[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  Foot best;
  std::vector<int> edges = B.at[near];
  for (int e : B.at[near]) {
    const auto [f, k] = B.edges[e];
    for (int v : {S.level.mesh.face_vertices(f)[k], S.level.mesh.face_vertices(f)[(k + 1) % 4]})
      for (int e2 : B.at[v])
        if (std::find(edges.begin(), edges.end(), e2) == edges.end()) edges.push_back(e2);
  }
  for (int e : edges) {
    const auto [f, k] = B.edges[e];
    const Samples::PtexMap& M = S.ptex[f];
    const double* p0 = co[k];
    const double* p1 = co[(k + 1) % 4];
    const int* fv = S.level.mesh.face_vertices(f);
    const Vec3 a = vec(X[fv[k]]), b = vec(X[fv[(k + 1) % 4]]);
    double x = std::clamp((t - a).dot(b - a) / std::max((b - a).squaredNorm(), 1e-300), 0.0, 1.0);
    LimitPoint q;
    Vec3 dx;
    auto eval = [&]() {
      const double s = p0[0] + x * (p1[0] - p0[0]), r = p0[1] + x * (p1[1] - p0[1]);
      double u, v;
      M.apply(s, r, u, v);
      q = E.evaluate_point(M.face, M.sub, std::clamp(u, 0.0, 1.0), std::clamp(v, 0.0, 1.0));
      const double ds = p1[0] - p0[0], dr = p1[1] - p0[1];
      dx = (ds * M.a[0] + dr * M.b[0]) * vec(q.du) + (ds * M.a[1] + dr * M.b[1]) * vec(q.dv);
    };
    eval();
    for (int iter = 0; iter < 10; ++iter) {
      const double g = dx.dot(vec(q.p) - t), hh = dx.squaredNorm();
      if (!(hh > 0)) break;
      const double nx = std::clamp(x - g / hh, 0.0, 1.0);
      const bool done = std::abs(nx - x) < 1e-15;
      x = nx;
      eval();
      if (done) break;
    }
    const double d2 = (vec(q.p) - t).squaredNorm();
    if (d2 >= best.distance2) continue;
    best.distance2 = d2;
    best.point = vec(q.p);
    best.normal = dx.norm() > 0 ? Vec3(dx.normalized()) : Vec3::Zero();
    best.grid = kExact;
    best.face = f;
    best.u = p0[0] + x * (p1[0] - p0[0]);
    best.v = p0[1] + x * (p1[1] - p0[1]);
  }
  return best;
}

}  // namespace

ShapeFitResult fit_to_shape(const SubdivLevel& cage, const std::vector<Point3>& start, const ShapeTarget& target,
                            const ShapeFitOptions& options, const ShapeFitProgress& progress) {
  const int n = cage.mesh.num_vertices();
  if (static_cast<int>(start.size()) != n) throw std::invalid_argument("fit_to_shape: one start position per cage vertex");
  if (options.levels < 1 || options.levels > 5) throw std::invalid_argument("fit_to_shape: levels must be 1..5");
  if (options.max_iterations < 0 || options.smoothing < 0 || options.target_weight < 0 || options.proximal < 0 ||
      !(options.min_gain >= 0) || !(options.crease_normal_weight >= 0) || !(options.crease_normal_guard >= 0) ||
      !(options.final_surface_weight > 0))
    throw std::invalid_argument("fit_to_shape: negative option");
  const double diag = target.diagonal();
  if (!(diag > 0)) throw std::invalid_argument("fit_to_shape: the target has no extent");
  for (const ShapeFitOptions::VertexPlane& c : options.vertex_planes)
    if (c.vertex < 0 || c.vertex >= n) throw std::invalid_argument("fit_to_shape: a held vertex out of range");

  // The energy matrix (serial, the set-up's longest part: about 0.2 s for fandisk's 1 124 quads)
  // on a thread of its own beside the samples and the exact rows' evaluators, when the loops may
  // use two threads (it holds a ThreadReservation meanwhile: the evaluators' loops take one fewer).
  Samples S;
  SparseMatrix K;
  const double lambda = options.smoothing / ptex_faces(cage);
  std::unique_ptr<ExactRows> exact;
  auto energy = [&] {
    if (lambda > 0) K = energy_matrix(cage, EnergyOptions{1.0, 0.0, 2});
  };
  auto rows = [&] {
    S = make_samples(cage, options.levels);
    exact = std::make_unique<ExactRows>(cage);
  };
  if (lambda > 0 && loop_threads() > 1) {
    std::exception_ptr error;
    std::thread beside([&] {
      const ThreadLimit one(1);
      const ThreadReservation core;
      try {
        energy();
      } catch (...) {
        error = std::current_exception();
      }
    });
    try {
      rows();
    } catch (...) {
      beside.join();
      throw;
    }
    beside.join();
    if (error) std::rethrow_exception(error);
  } else {
    rows();
    energy();
  }
  const int ns = static_cast<int>(S.vertex.size());
  if (ns == 0) throw std::invalid_argument("fit_to_shape: the cage has no limit surface");
  std::optional<LimitEvaluator> E;
  // The normal equations keep one structure through the fit: every pair of vertices in one cage
  // face's support (any limit point's row, hence any sample's or foot's, lies in one), so that
  // the symbolic factorisation is done once.
  NormalEquations eq(n);
  for (int f = 0; f < cage.mesh.num_faces(); ++f) {
    if (cage.face_hole[f]) continue;
    const std::vector<int>& sup = exact->support[f];
    for (int a : sup)
      for (int b : sup)
        if (a <= b) eq.block_index(a, b);
  }
  const SampleGroups groups(cage, S, *exact, eq);
  const std::vector<Point3>& data = target.data_points();
  const int nb = static_cast<int>(data.size());
  const double wa1 = 1.0 / ns, wb = options.target_weight / nb;
  const double final_surface = options.final_surface_weight;
  const bool can_plane = target.has_normals() && options.plane_iterations > 0;

  ShapeFitResult result;
  result.samples = ns;
  std::vector<Point3> P = start;
  std::vector<Point3> X, Y, xs(ns);
  std::vector<Vec3> normal;
  std::vector<ShapeTarget::Closest> closest(ns);
  // The border: the target's boundary vertices against the surface's border curve (exact).
  const Border B = surface_border(S.level);
  std::vector<int> tborder =
      exact && target.has_triangles() && !B.edges.empty() ? target_border(target) : std::vector<int>{};
  // Crease curves: the target's feature vertices against the surface's sharp curves (exact),
  // where one is near (within crease_reach level-k crease edges).
  const Border C = surface_border(S.level, true);
  std::vector<int> tcrease;
  if (target.has_triangles() && !C.edges.empty() && options.crease_angle > 0)
    tcrease = target_creases(target, options.crease_angle);
  for (int v : tcrease) tborder.push_back(v);
  // The crease sides' normals (options.crease_normal_weight): at the middle of each level-k
  // crease edge in a cage face at a corner, on both sides.
  std::vector<CreaseNormal> crease_normals;
  if (options.crease_normal_weight > 0 && target.has_triangles()) {
    static const double co[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    const PolyMesh& mk = S.level.mesh;
    for (const auto& [f0, k0] : C.edges) {
      const int h0 = mk.face_begin(f0) + k0;
      for (const int h : {h0, mk.twin(h0)}) {
        const int f = mk.corner_face(h), k = h - mk.face_begin(f);
        if (mk.face_size(f) != 4 || S.level.face_hole[f]) continue;
        const double* p0 = co[k];
        const double* p1 = co[(k + 1) % 4];
        const double* p3 = co[(k + 3) % 4];
        const double s0 = 0.5 * (p0[0] + p1[0]), t0 = 0.5 * (p0[1] + p1[1]);
        const double ds = p3[0] - p0[0], dt = p3[1] - p0[1];
        const double es = p1[0] - p0[0], et = p1[1] - p0[1];
        const Samples::PtexMap& M = S.ptex[f];
        // Only in the cage faces at a corner (a vertex tagged infinitely sharp), where feature
        // curves meet: the wedges. Elsewhere a quad meets its crease about square, and the rows
        // only disturbed the fit of noisy CAD edges (docs/fitting.md).
        bool at_corner = false;
        const int* cv = cage.mesh.face_vertices(M.face);
        for (int j = 0; j < cage.mesh.face_size(M.face); ++j)
          at_corner = at_corner || cage.vertex_sharpness[cv[j]] >= kInfiniteSharpness;
        if (!at_corner) continue;
        CreaseNormal c;
        c.face = M.face;
        c.sub = M.sub;
        double u, v;
        M.apply(s0, t0, u, v);
        const double along[2] = {es * M.a[0] + et * M.b[0], es * M.a[1] + et * M.b[1]};
        const double across[2] = {ds * M.a[0] + dt * M.b[0], ds * M.a[1] + dt * M.b[1]};
        exact->derivative_rows(M.face, M.sub, u, v, along, across, c.idx, c.wT, c.wD);
        M.apply(s0 + 0.5 * ds, t0 + 0.5 * dt, c.qu, c.qv);
        crease_normals.push_back(std::move(c));
      }
    }
  }
  const double wcn = options.crease_normal_weight / ns;
  constexpr double kMaxConditioning = 10;  // 1 / sin^2 - 1 at 17.5 deg
  const double cos_guard = std::cos(options.crease_normal_guard * kPi / 180.0);
  const int nborder = static_cast<int>(tborder.size()) - static_cast<int>(tcrease.size());
  const int nbd = static_cast<int>(tborder.size());
  const double wbd_border = options.target_weight / std::max(nborder, 1);
  const double wcr = options.target_weight / std::max(nbd - nborder, 1);
  std::vector<char> paired(nbd, 1);
  std::vector<Foot> foot(nb + nbd);
  // Per row of A (surface -> target) and of B (target -> surface): the symmetric 3 x 3 weight
  // (xx, yy, zz, xy, xz, yz) and W c.
  Eigen::MatrixXd Ma(ns, 6), Ga(ns, 3), Mb(nb + nbd, 6), Gb(nb + nbd, 3);
  bool plane = can_plane, last_plane = can_plane;
  int plane_count = 0;
  double prev_objective = std::numeric_limits<double>::infinity();
  double plane_w = 0;  // the held vertices' weight in the last solve (0 before the first)
  double prev_distance = std::numeric_limits<double>::infinity();
  double damping = 0;
  struct {
    std::vector<Point3> P;
    std::vector<Foot> foot;
    Eigen::MatrixXd Ma, Ga, Mb, Gb;
    std::vector<CreaseNormal::State> crease_normals;
    ShapeFitIteration h;
  } accepted;
  auto put = [](Eigen::MatrixXd& M, Eigen::MatrixXd& G, int i, const Eigen::Matrix3d& W, const Vec3& c) {
    M.row(i) << W(0, 0), W(1, 1), W(2, 2), W(0, 1), W(0, 2), W(1, 2);
    G.row(i) = (W * c).transpose();
  };

  for (int it = 0;; ++it) {
    // Pairing at the current cage.
    S.to_level.apply(P, Y);
    S.limit.apply(Y, X);
    for (int i = 0; i < ns; ++i) xs[i] = X[S.vertex[i]];
    sample_normals(S.level, X, normal);
    if (exact) E.emplace(cage, P);
    parallel_for(ns, [&](int i) { closest[i] = target.closest(xs[i], closest[i].element); });
    const ClosestPointTree sample_tree(xs, {});
    parallel_for(nb, [&](int j) {
      const Vec3 t = vec(data[j]);
      foot[j] = foot_point(S, Y, X, normal, E ? &*E : nullptr, t, S.vertex[sample_tree.closest(data[j]).element]);
    });
    if (nborder > 0) {
      std::vector<Point3> bx;
      for (int v : B.vertices) bx.push_back(X[v]);
      const ClosestPointTree border_tree(bx, {});
      parallel_for(nborder, [&](int j) {
        const Point3& t = target.points()[tborder[j]];
        foot[nb + j] = border_foot(S, B, *E, X, vec(t), B.vertices[border_tree.closest(t).element]);
      });
    }
    if (nbd > nborder) {
      std::vector<Point3> cx;
      double h = 0;
      for (int v : C.vertices) cx.push_back(X[v]);
      for (const auto& [f, k] : C.edges) {
        const int* fv = S.level.mesh.face_vertices(f);
        h += (vec(X[fv[k]]) - vec(X[fv[(k + 1) % 4]])).norm();
      }
      h /= static_cast<double>(C.edges.size());
      const ClosestPointTree crease_tree(cx, {});
      parallel_for(nbd - nborder, [&](int i) {
        const int j = nborder + i;
        const Point3& t = target.points()[tborder[j]];
        foot[nb + j] = border_foot(S, C, *E, X, vec(t), C.vertices[crease_tree.closest(t).element]);
        paired[j] = std::sqrt(foot[nb + j].distance2) <= options.crease_reach * h;
      });
    }

    parallel_for(static_cast<int>(crease_normals.size()), [&](int i) {
      CreaseNormal& c = crease_normals[i];
      CreaseNormal::State& st = c.state;
      st.weight = 0;
      const LimitPoint q = E->evaluate_point(c.face, c.sub, c.qu, c.qv);
      const Vec3 nq = vec(q.du).cross(vec(q.dv));
      const ShapeTarget::Closest hit = target.closest(q.p, c.hint);
      c.hint = hit.element;
      // The triangle's own normal (closest()'s is interpolated from vertex normals, which a
      // sharp edge's vertices smear across it).
      const auto& tri = target.triangles()[static_cast<std::size_t>(hit.element)];
      const Vec3 ta = vec(target.points()[tri[0]]);
      const Vec3 tn = (vec(target.points()[tri[1]]) - ta).cross(vec(target.points()[tri[2]]) - ta);
      // Signed: the cage faces the mesh's way (a wall's other side, facing away, is not its normal).
      if (!(tn.norm() > 0 && nq.norm() > 0) || tn.normalized().dot(nq) < cos_guard * nq.norm()) return;
      const Vec3 nt = tn.normalized();
      Vec3 T = Vec3::Zero(), D = Vec3::Zero();
      for (std::size_t k = 0; k < c.idx.size(); ++k) {
        T += c.wT[k] * vec(P[c.idx[k]]);
        D += c.wD[k] * vec(P[c.idx[k]]);
      }
      const Vec3 t = T - nt.dot(T) * nt;
      if (!(t.norm() > 0 && T.norm() > 0)) return;
      const Vec3 tu = t.normalized();
      const Vec3 e = nt.cross(tu);
      const double a = D.dot(tu), b = D.dot(e), len = D.norm();
      if (!(std::abs(b) > 1e-3 * len)) return;
      // residual across (e): (a / b) (n.T) / |T| - (n.D) / b; along (t): -(n.T) / |T|; times |D|.
      st.across.resize(c.idx.size());
      st.along.resize(c.idx.size());
      for (std::size_t k = 0; k < c.idx.size(); ++k) {
        st.across[k] = len * (a / b * c.wT[k] / T.norm() - c.wD[k] / b);
        st.along[k] = len * c.wT[k] / T.norm();
      }
      st.normal = nt;
      // Weighted by the ill-conditioning 1 / sin^2 - 1 of the angle between T and D: nothing
      // where the quad meets the crease square (the positions hold the normal there), 10 x at
      // fandisk's fan tip (17 deg); capped there (a degenerate corner quad, D almost along T,
      // would otherwise outweigh every position around it).
      const double sin2 = b * b / (len * len);
      st.weight = wcn * std::min(1 / sin2 - 1, kMaxConditioning);
    });

    // Weights and the objective.
    ShapeFitIteration h;
    h.point_to_plane = plane;
    double data_sum = 0, sa = 0, sb = 0;
    const double wa = plane ? wa1 : wa1 * final_surface;
    for (int i = 0; i < ns; ++i) {
      const Vec3 x = vec(xs[i]), c = vec(closest[i].point), d = x - c;
      sa += d.squaredNorm();
      h.surface_max = std::max(h.surface_max, d.norm());
      const Vec3 nt = vec(closest[i].normal);
      const double along = nt.dot(d);
      // Point-to-plane only where the closest point is a foot along the target's normal; where
      // the sample lies beyond the target's border, the whole distance (else the surface could
      // grow past an open target's border for free).
      if (plane && d.squaredNorm() - along * along <= 0.0625 * d.squaredNorm()) {
        put(Ma, Ga, i, wa * nt * nt.transpose(), c);
        data_sum += wa * along * along;
      } else {
        put(Ma, Ga, i, wa * Eigen::Matrix3d::Identity(), c);
        data_sum += wa * d.squaredNorm();
      }
    }
    for (int j = 0; j < nb; ++j) {
      const Foot& f = foot[j];
      const Vec3 t = vec(data[j]), d = f.point - t;
      const double along = f.normal.dot(d), d2 = d.squaredNorm();
      // At a foot inside the surface d is along the normal: measured to the tangent plane. Where
      // the foot is on the surface's border (t beyond a boundary) d is tangential: the whole
      // distance, so that the surface reaches t.
      // With the border term (a triangle target with a boundary) the surface's border is held
      // by it, and every foot is measured along the normal.
      const bool to_plane = nborder > 0 || B.edges.empty() || d2 - along * along <= 0.0625 * d2;
      const double r2 = to_plane ? along * along : d2;
      sb += r2;
      h.target_max = std::max(h.target_max, std::sqrt(r2));
      data_sum += wb * r2;
      put(Mb, Gb, j, to_plane ? Eigen::Matrix3d(wb * f.normal * f.normal.transpose())
                              : Eigen::Matrix3d(wb * Eigen::Matrix3d::Identity()), t);
    }
    for (int j = 0; j < nbd; ++j) {
      const Foot& f = foot[nb + j];
      const double wbd = j < nborder ? wbd_border : paired[j] ? wcr : 0.0;
      const Vec3 t = vec(target.points()[tborder[j]]), d = f.point - t, tau = f.normal;
      const Vec3 perp = d - d.dot(tau) * tau;
      // Across the curve where the foot is inside it; the whole distance beyond its end.
      const bool across = perp.squaredNorm() >= 0.9375 * d.squaredNorm();
      data_sum += wbd * (across ? perp.squaredNorm() : d.squaredNorm());
      put(Mb, Gb, nb + j,
          across ? Eigen::Matrix3d(wbd * (Eigen::Matrix3d::Identity() - tau * tau.transpose()))
                 : Eigen::Matrix3d(wbd * Eigen::Matrix3d::Identity()),
          t);
    }
    // The crease normals' rows are in the solves but not in this objective (the step control):
    // their frames and the rows in use change from one iteration to the next, and counted here
    // they made the step control reject steps (featuretype: its distances' rms 1.2e-4 -> 1.9e-4).
    double reg = 0;
    if (lambda > 0)
      for (int c = 0; c < 3; ++c) {
        Eigen::VectorXd p(n);
        for (int v = 0; v < n; ++v) p[v] = P[v][c];
        reg += lambda * p.dot(K * p);
      }
    for (const ShapeFitOptions::VertexPlane& c : options.vertex_planes) {
      const double off = c.normal[0] * P[c.vertex][0] + c.normal[1] * P[c.vertex][1] + c.normal[2] * P[c.vertex][2] - c.offset;
      reg += plane_w * off * off;
    }
    h.objective = (data_sum + reg) / (diag * diag);
    h.surface_rms = std::sqrt(sa / ns) / diag;
    h.surface_max /= diag;
    h.target_rms = std::sqrt(sb / nb) / diag;
    h.target_max /= diag;
    result.history.push_back(h);

    // Step control (Levenberg-Marquardt): a solve that made the objective of the same phase
    // worse is undone, and solved again from the last accepted pairing with a larger damping.
    double improvement = (prev_objective - h.objective) / std::max(prev_objective, 1e-300);
    const bool same_phase = it > 0 && plane == last_plane;
    if (same_phase && improvement < 0 && !(h.surface_rms <= options.tolerance && h.target_rms <= options.tolerance)) {
      damping = damping > 0 ? 10 * damping : 1e-6;
      if (damping > 1e3 || it >= options.max_iterations) {  // no descent left: the accepted state is the result
        P = accepted.P;
        result.history.back() = accepted.h;
        result.stop = damping > 1e3 ? ShapeFitStop::Converged : ShapeFitStop::IterationLimit;
        break;
      }
      P = accepted.P;
      foot = accepted.foot;
      Ma = accepted.Ma;
      Ga = accepted.Ga;
      Mb = accepted.Mb;
      Gb = accepted.Gb;
      for (std::size_t i = 0; i < crease_normals.size(); ++i) crease_normals[i].state = accepted.crease_normals[i];
      result.history.back() = accepted.h;
      plane_w = solve_step(S, exact.get(), foot, Ma, Ga, Mb, Gb, K, lambda, options.proximal + damping, groups, options, crease_normals, eq, P);
      result.iterations = it + 1;
      continue;
    }
    if (same_phase) damping = damping > 1e-9 ? damping / 10 : 0;
    // The measured two-sided RMS distance and its gain in this iteration (independent of the
    // phase: the surface -> target part is always the whole distance).
    const double distance = std::sqrt(0.5 * (h.surface_rms * h.surface_rms + h.target_rms * h.target_rms));
    const bool stalled = it > 0 && prev_distance - distance < options.min_gain * distance;
    if (h.surface_rms <= options.tolerance && h.target_rms <= options.tolerance) {
      result.stop = ShapeFitStop::Tolerance;
      break;
    }
    if (!plane && same_phase && (improvement < options.min_improvement || stalled)) {
      result.stop = ShapeFitStop::Converged;
      break;
    }
    if (it >= options.max_iterations) {
      result.stop = ShapeFitStop::IterationLimit;
      break;
    }
    if (progress && !progress(it, h.objective)) {
      result.stop = ShapeFitStop::Cancelled;
      break;
    }
    last_plane = plane;
    prev_objective = h.objective;
    prev_distance = distance;
    if (plane) {
      ++plane_count;
      if (plane_count >= options.plane_iterations || (it > 0 && (improvement < options.plane_switch || stalled))) {
        plane = false;
        prev_objective = std::numeric_limits<double>::infinity();
      }
    }

    accepted.P = P;
    accepted.foot = foot;
    accepted.Ma = Ma;
    accepted.Ga = Ga;
    accepted.Mb = Mb;
    accepted.Gb = Gb;
    accepted.crease_normals.resize(crease_normals.size());
    for (std::size_t i = 0; i < crease_normals.size(); ++i) accepted.crease_normals[i] = crease_normals[i].state;
    accepted.h = h;
    plane_w = solve_step(S, exact.get(), foot, Ma, Ga, Mb, Gb, K, lambda, options.proximal + damping, groups, options, crease_normals, eq, P);
    result.iterations = it + 1;
  }
  const ShapeFitIteration& last = result.history.back();
  result.surface_rms = last.surface_rms;
  result.surface_max = last.surface_max;
  result.target_rms = last.target_rms;
  result.target_max = last.target_max;
  result.positions = std::move(P);
  return result;
}

std::vector<int> feature_edges_on_target(const SubdivLevel& cage, const std::vector<Point3>& positions,
                                         const ShapeTarget& target, double angle_degrees, double reach) {
  const PolyMesh& m = cage.mesh;
  if (static_cast<int>(positions.size()) != m.num_vertices())
    throw std::invalid_argument("feature_edges_on_target: one position per cage vertex");
  if (!target.has_triangles()) return {};
  const FeatureSet fs = target_features(target, angle_degrees);
  if (fs.edges.empty()) return {};
  // Feature curves: the feature edges joined through vertices of two feature edges that are no
  // corner.
  const int np = static_cast<int>(target.points().size()), ne = static_cast<int>(fs.edges.size());
  std::vector<std::vector<int>> at(np);
  for (int i = 0; i < ne; ++i)
    for (int v : fs.edges[i]) at[v].push_back(i);
  std::vector<char> corner(np, 0);
  for (int v : fs.corners) corner[v] = 1;
  std::vector<int> curve(ne, -1);
  int curves = 0;
  for (int i = 0; i < ne; ++i) {
    if (curve[i] >= 0) continue;
    std::vector<int> stack = {i};
    curve[i] = curves;
    while (!stack.empty()) {
      const int e = stack.back();
      stack.pop_back();
      for (int v : fs.edges[e]) {
        if (corner[v] || at[v].size() != 2) continue;
        for (int e2 : at[v])
          if (curve[e2] < 0) {
            curve[e2] = curves;
            stack.push_back(e2);
          }
      }
    }
    ++curves;
  }
  // Points along the feature edges (ends included), each with its edge and end.
  constexpr int per = 8;
  std::vector<Point3> pts;
  std::vector<std::pair<int, int>> owner;  // (edge, k of 0..per)
  for (int i = 0; i < ne; ++i) {
    const Point3& a = target.points()[fs.edges[i][0]];
    const Point3& b = target.points()[fs.edges[i][1]];
    for (int k = 0; k <= per; ++k) {
      const double t = static_cast<double>(k) / per;
      pts.push_back({a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])});
      owner.push_back({i, k});
    }
  }
  const ClosestPointTree tree(pts, {});
  // The curves that pass within r of q (a point at a feature vertex on all the curves there).
  auto near = [&](const Point3& q, double r, std::vector<int>& out) {
    out.clear();
    for (;;) {
      const ClosestPointTree::Hit h = tree.closest_if(q, [&](int s) {
        return std::find(out.begin(), out.end(), curve[owner[s].first]) == out.end();
      });
      if (h.element < 0 || h.distance2 > r * r) break;
      const auto [e, k] = owner[h.element];
      if (k == 0 || k == per) {
        for (int e2 : at[fs.edges[e][k == 0 ? 0 : 1]])
          if (std::find(out.begin(), out.end(), curve[e2]) == out.end()) out.push_back(curve[e2]);
      } else {
        out.push_back(curve[e]);
      }
    }
    std::sort(out.begin(), out.end());
  };
  // Each vertex's shortest edge: the reach is a fraction of the local spacing (a long edge
  // beside a feature, a short one away, is not along it).
  std::vector<double> shortest(m.num_vertices(), std::numeric_limits<double>::infinity());
  for (int e = 0; e < m.num_edges(); ++e) {
    const int a = m.edge_vertex(e, 0), b = m.edge_vertex(e, 1);
    const double len = (vec(positions[b]) - vec(positions[a])).norm();
    shortest[a] = std::min(shortest[a], len);
    shortest[b] = std::min(shortest[b], len);
  }
  std::vector<int> out, ca, cb, cm, ab;
  for (int e = 0; e < m.num_edges(); ++e) {
    if (m.is_boundary_edge(e) || cage.infinitely_sharp(e)) continue;
    const int h = m.edge_corner(e);
    const int f = m.corner_face(h), tw = m.twin(h);
    if (cage.face_hole[f] || (tw >= 0 && cage.face_hole[m.corner_face(tw)])) continue;
    const Point3& a = positions[m.edge_vertex(e, 0)];
    const Point3& b = positions[m.edge_vertex(e, 1)];
    const Vec3 d = vec(b) - vec(a);
    const double r = reach * std::min({d.norm(), shortest[m.edge_vertex(e, 0)], shortest[m.edge_vertex(e, 1)]});
    if (!(r > 0)) continue;
    near(a, r, ca);
    near(b, r, cb);
    near({0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])}, r, cm);
    ab.clear();
    std::set_intersection(ca.begin(), ca.end(), cb.begin(), cb.end(), std::back_inserter(ab));
    bool shared = false;
    for (int c : cm) shared = shared || std::binary_search(ab.begin(), ab.end(), c);
    if (shared) out.push_back(e);
  }
  return out;
}

Similarity register_to_target(const std::vector<Point3>& points, const ShapeTarget& target, int iterations) {
  if (points.empty()) throw std::invalid_argument("register_to_target: no points");
  const double diag = target.diagonal();
  auto box = [](const std::vector<Point3>& p, Vec3& centre) {
    Vec3 lo = vec(p[0]), hi = lo;
    for (const Point3& q : p) {
      lo = lo.cwiseMin(vec(q));
      hi = hi.cwiseMax(vec(q));
    }
    centre = (lo + hi) / 2;
    return (hi - lo).norm();
  };
  Vec3 cp, ct;
  const double dp = box(points, cp), dt = box(target.points(), ct);
  if (!(dp > 0)) throw std::invalid_argument("register_to_target: the points have no extent");
  const int n = static_cast<int>(points.size());
  std::vector<Point3> mapped(n);
  std::vector<ShapeTarget::Closest> closest(n);
  // stride > 1: every stride-th point only (the 24 trials: which rotation fits best shows on a
  // few thousand points, and far from the target each query is costly).
  auto rms_of = [&](const Eigen::Matrix3d& R, double s, const Vec3& t, int stride = 1) {
    const int m = (n + stride - 1) / stride;
    for (int k = 0; k < m; ++k) {
      const Vec3 q = s * R * vec(points[k * stride]) + t;
      mapped[k * stride] = {q[0], q[1], q[2]};
    }
    parallel_for(m, [&](int k) {
      const int i = k * stride;
      closest[i] = target.closest(mapped[i], closest[i].element);
    });
    double sum = 0;
    for (int k = 0; k < m; ++k) sum += closest[k * stride].distance * closest[k * stride].distance;
    return std::sqrt(sum / m);
  };
  const int trial_stride = std::max(1, n / 2048);
  // The 24 rotations that map axes to axes.
  Eigen::Matrix3d bestR = Eigen::Matrix3d::Identity();
  double best = std::numeric_limits<double>::infinity(), s = dt / dp;
  Vec3 t = ct - s * cp;
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (const auto& pm : perms)
    for (int signs = 0; signs < 8; ++signs) {
      Eigen::Matrix3d R = Eigen::Matrix3d::Zero();
      for (int i = 0; i < 3; ++i) R(i, pm[i]) = (signs >> i) & 1 ? -1.0 : 1.0;
      if (R.determinant() < 0) continue;
      const Vec3 tr = ct - s * R * cp;
      const double r = rms_of(R, s, tr, trial_stride);
      if (r < best) {
        best = r;
        bestR = R;
        t = tr;
      }
    }
  // Closest-point iterations with Umeyama's similarity.
  Eigen::Matrix3d R = bestR;
  double prev = std::numeric_limits<double>::infinity();
  for (int it = 0; it < iterations; ++it) {
    const double r = rms_of(R, s, t);
    if (!(r < prev * (1 - 1e-9))) break;
    prev = r;
    Vec3 mx = Vec3::Zero(), my = Vec3::Zero();
    for (int i = 0; i < n; ++i) {
      mx += vec(points[i]);
      my += vec(closest[i].point);
    }
    mx /= n;
    my /= n;
    Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
    double vx = 0;
    for (int i = 0; i < n; ++i) {
      const Vec3 a = vec(points[i]) - mx, b = vec(closest[i].point) - my;
      C += b * a.transpose();
      vx += a.squaredNorm();
    }
    C /= n;
    vx /= n;
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(C, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
    if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0) D(2, 2) = -1;
    R = svd.matrixU() * D * svd.matrixV().transpose();
    s = (svd.singularValues().asDiagonal() * D).trace() / vx;
    t = my - s * R * mx;
  }
  Similarity out;
  out.scale = s;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) out.R[i][j] = R(i, j);
    out.t[i] = t[i];
  }
  out.rms = rms_of(R, s, t) / diag;
  return out;
}

}  // namespace subd2nurbs
