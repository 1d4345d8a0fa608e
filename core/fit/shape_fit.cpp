#include "core/fit/shape_fit.h"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cstdint>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/fit/fairing.h"
#include "core/fit/interpolate.h"
#include "core/fit/limit_rows.h"
#include "core/fit/sparse_util.h"
#include "core/refine/quad_grid.h"
#include "core/util/bicubic.h"
#include "core/util/parallel.h"

namespace subd2nurbs {

using fit_detail::SparseMatrix;

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
};

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
  int grid = -1;                 ///< B-spline patch (index into Samples::grids), or -1: triangle
  double u = 0, v = 0;           ///< B-spline parameters
  std::array<int, 3> tri{};      ///< triangle: level-k vertices
  std::array<double, 3> bary{};  ///< and barycentric weights
};

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
    const Vec3 r = vec(p) - t, a = vec(du), b = vec(dv);
    Eigen::Matrix2d JtJ;
    JtJ << a.dot(a), a.dot(b), a.dot(b), b.dot(b);
    const Eigen::Vector2d step = JtJ.ldlt().solve(-Eigen::Vector2d(a.dot(r), b.dot(r)));
    if (!step.allFinite()) break;
    const double nu = std::clamp(u + step[0], 0.0, 1.0), nv = std::clamp(v + step[1], 0.0, 1.0);
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
                const std::vector<Vec3>& normal, const Vec3& t, int near) {
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
  const bool inside = best.grid >= 0 ? best.u > 0 && best.u < 1 && best.v > 0 && best.v < 1
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
struct NormalEquations {
  int n = 0;
  std::vector<std::uint64_t> keys;   ///< table slots: a n + b + 1, 0 for an empty slot
  std::vector<int> slot_block;       ///< table slot -> block index
  std::vector<int> block_a, block_b; ///< per block: its vertex pair
  std::vector<double> blocks;        ///< 9 per block, row-major
  Eigen::VectorXd rhs;               ///< coordinate-major: x of every vertex, then y, then z

  explicit NormalEquations(int vertices) : n(vertices), rhs(Eigen::VectorXd::Zero(3 * n)) {
    std::size_t capacity = 1024;
    while (capacity < static_cast<std::size_t>(n) * 128) capacity *= 2;
    keys.assign(capacity, 0);
    slot_block.assign(capacity, -1);
  }
  /// The block of (a, b), a <= b, created zero on first use.
  double* block(int a, int b) {
    const std::uint64_t key = static_cast<std::uint64_t>(a) * static_cast<std::uint64_t>(n) + static_cast<std::uint64_t>(b) + 1;
    std::size_t mask = keys.size() - 1, i = static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> 20) & mask;
    while (keys[i] != 0 && keys[i] != key) i = (i + 1) & mask;
    if (keys[i] == 0) {
      if (2 * (block_a.size() + 1) > keys.size()) {  // keep the load at most 1/2
        grow();
        return block(a, b);
      }
      keys[i] = key;
      slot_block[i] = static_cast<int>(block_a.size());
      block_a.push_back(a);
      block_b.push_back(b);
      blocks.resize(blocks.size() + 9, 0.0);
    }
    return &blocks[static_cast<std::size_t>(9) * static_cast<std::size_t>(slot_block[i])];
  }
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
  /// The sparse matrix (coordinate-major) with lambda K (x) I3 + mu I added.
  SparseMatrix matrix(const SparseMatrix* K, double lambda, double mu) const {
    std::vector<Eigen::Triplet<double>> trip;
    trip.reserve(18 * block_a.size() + 3 * static_cast<std::size_t>(n) * (K ? 26 : 1));
    for (std::size_t i = 0; i < block_a.size(); ++i) {
      const int a = block_a[i], b = block_b[i];
      const double* blk = &blocks[9 * i];
      bool any = false;  // a block is entered whole (its zeros too) when any entry is not zero
      for (int k = 0; k < 9 && !any; ++k) any = blk[k] != 0;
      if (!any) continue;
      for (int k = 0; k < 9; ++k) {
        trip.emplace_back((k / 3) * n + a, (k % 3) * n + b, blk[k]);
        if (b != a) trip.emplace_back((k % 3) * n + b, (k / 3) * n + a, blk[k]);
      }
    }
    for (int c = 0; c < 3; ++c) {
      if (K)
        for (int col = 0; col < n; ++col)
          for (SparseMatrix::InnerIterator e(*K, col); e; ++e)
            trip.emplace_back(c * n + static_cast<int>(e.row()), c * n + col, lambda * e.value());
      for (int v = 0; v < n; ++v) trip.emplace_back(c * n + v, c * n + v, mu);
    }
    SparseMatrix H(3 * n, 3 * n);
    H.setFromTriplets(trip.begin(), trip.end());
    return H;
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

/// One solve of a fit iteration: the cage positions minimising the weighted pairings (rows of A:
/// samples -> targets, weights Ma, W c Ga; rows of B: data points -> their feet, Mb, Gb) plus the
/// regulariser lambda K and the proximal term mu |P - P_prev|^2. \throw FitError
void solve_step(const Samples& S, const std::vector<Foot>& foot, const Eigen::MatrixXd& Ma, const Eigen::MatrixXd& Ga,
                const Eigen::MatrixXd& Mb, const Eigen::MatrixXd& Gb, const SparseMatrix& K, double lambda,
                double proximal, std::vector<Point3>& P) {
  const int n = static_cast<int>(P.size()), ns = static_cast<int>(S.vertex.size()), nb = static_cast<int>(foot.size());
  // Solve (H + lambda K (x) I3 + mu I) P = rhs + mu P_prev, H = sum over the rows (samples,
  // then data points; each over the cage) of r^T r (x) W.
  NormalEquations eq(n);
  auto weight = [](const Eigen::MatrixXd& M, int i) {
    Eigen::Matrix3d W;
    W << M(i, 0), M(i, 3), M(i, 4), M(i, 3), M(i, 1), M(i, 5), M(i, 4), M(i, 5), M(i, 2);
    return W;
  };
  for (int i = 0; i < ns; ++i) {
    const int v = S.vertex[i], o = S.all_rows.offsets[v];
    eq.add(&S.all_rows.indices[o], &S.all_rows.weights[o], S.all_rows.row_size(v), weight(Ma, i), Ga.row(i).transpose());
  }
  RowSum row(n);
  for (int j = 0; j < nb; ++j) {
    const Foot& f = foot[j];
    row.clear();
    if (f.grid >= 0) {
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
  const double mu = proximal * eq.trace() / (3.0 * n) + 1e-300;
  const SparseMatrix H = eq.matrix(lambda > 0 ? &K : nullptr, lambda, mu);
  Eigen::VectorXd rhs = eq.rhs;
  for (int c = 0; c < 3; ++c)
    for (int v = 0; v < n; ++v) rhs[c * n + v] += mu * P[v][c];
  Eigen::SimplicialLDLT<SparseMatrix> ldlt(H);
  if (ldlt.info() != Eigen::Success) throw FitError("fit_to_shape: the normal equations could not be factorised", {});
  const Eigen::VectorXd x = ldlt.solve(rhs);
  if (!x.allFinite()) throw FitError("fit_to_shape: the solve gave non-finite positions", {});
  for (int v = 0; v < n; ++v) P[v] = {x[v], x[n + v], x[2 * n + v]};
}

}  // namespace

ShapeFitResult fit_to_shape(const SubdivLevel& cage, const std::vector<Point3>& start, const ShapeTarget& target,
                            const ShapeFitOptions& options, const ShapeFitProgress& progress) {
  const int n = cage.mesh.num_vertices();
  if (static_cast<int>(start.size()) != n) throw std::invalid_argument("fit_to_shape: one start position per cage vertex");
  if (options.levels < 1 || options.levels > 5) throw std::invalid_argument("fit_to_shape: levels must be 1..5");
  if (options.max_iterations < 0 || options.smoothing < 0 || options.target_weight < 0 || options.proximal < 0)
    throw std::invalid_argument("fit_to_shape: negative option");
  const double diag = target.diagonal();
  if (!(diag > 0)) throw std::invalid_argument("fit_to_shape: the target has no extent");

  const Samples S = make_samples(cage, options.levels);
  const int ns = static_cast<int>(S.vertex.size());
  if (ns == 0) throw std::invalid_argument("fit_to_shape: the cage has no limit surface");
  SparseMatrix K;
  const double lambda = options.smoothing / ptex_faces(cage);
  if (lambda > 0) K = energy_matrix(cage, EnergyOptions{1.0, 0.0, 2});

  const std::vector<Point3>& data = target.data_points();
  const int nb = static_cast<int>(data.size());
  const double wa = 1.0 / ns, wb = options.target_weight / nb;
  const bool can_plane = target.has_normals() && options.plane_iterations > 0;

  ShapeFitResult result;
  result.samples = ns;
  std::vector<Point3> P = start;
  std::vector<Point3> X, Y, xs(ns);
  std::vector<Vec3> normal;
  std::vector<ShapeTarget::Closest> closest(ns);
  std::vector<Foot> foot(nb);
  // Per row of A (surface -> target) and of B (target -> surface): the symmetric 3 x 3 weight
  // (xx, yy, zz, xy, xz, yz) and W c.
  Eigen::MatrixXd Ma(ns, 6), Ga(ns, 3), Mb(nb, 6), Gb(nb, 3);
  bool plane = can_plane, last_plane = can_plane;
  int plane_count = 0;
  double prev_objective = std::numeric_limits<double>::infinity();
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
    parallel_for(ns, [&](int i) { closest[i] = target.closest(xs[i]); });
    const ClosestPointTree sample_tree(xs, {});
    parallel_for(nb, [&](int j) {
      const Vec3 t = vec(data[j]);
      foot[j] = foot_point(S, Y, X, normal, t, S.vertex[sample_tree.closest(data[j]).element]);
    });

    // Weights and the objective.
    ShapeFitIteration h;
    h.point_to_plane = plane;
    double data_sum = 0, sa = 0, sb = 0;
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
      const bool to_plane = d2 - along * along <= 0.0625 * d2;
      const double r2 = to_plane ? along * along : d2;
      sb += r2;
      h.target_max = std::max(h.target_max, std::sqrt(r2));
      data_sum += wb * r2;
      put(Mb, Gb, j, to_plane ? Eigen::Matrix3d(wb * f.normal * f.normal.transpose())
                              : Eigen::Matrix3d(wb * Eigen::Matrix3d::Identity()), t);
    }
    double reg = 0;
    if (lambda > 0)
      for (int c = 0; c < 3; ++c) {
        Eigen::VectorXd p(n);
        for (int v = 0; v < n; ++v) p[v] = P[v][c];
        reg += lambda * p.dot(K * p);
      }
    h.objective = (data_sum + reg) / (diag * diag);
    h.surface_rms = std::sqrt(sa / ns) / diag;
    h.surface_max /= diag;
    h.target_rms = std::sqrt(sb / nb) / diag;
    h.target_max /= diag;
    result.history.push_back(h);

    // Stop rules.
    const double improvement = (prev_objective - h.objective) / std::max(prev_objective, 1e-300);
    const bool same_phase = it > 0 && plane == last_plane;
    if (h.surface_rms <= options.tolerance && h.target_rms <= options.tolerance) {
      result.stop = ShapeFitStop::Tolerance;
      break;
    }
    if (!plane && same_phase && improvement < options.min_improvement) {
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
    if (plane) {
      ++plane_count;
      if (plane_count >= options.plane_iterations || (it > 0 && improvement < options.plane_switch)) {
        plane = false;
        prev_objective = std::numeric_limits<double>::infinity();
      }
    }

    solve_step(S, foot, Ma, Ga, Mb, Gb, K, lambda, options.proximal, P);
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

}  // namespace subd2nurbs
