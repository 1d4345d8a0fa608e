#include "core/fit/fairing.h"

#include <Eigen/SparseCholesky>
#include <array>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/fit/interpolate.h"
#include "core/fit/limit_rows.h"
#include "core/fit/sparse_util.h"

namespace subd2nurbs {

using fit_detail::SparseMatrix;

namespace {

/// Uniform cubic B-spline basis on one span and its first two derivatives.
void basis(double t, double n[3][4]) {
  const double s = 1 - t;
  n[0][0] = s * s * s / 6;
  n[0][1] = (3 * t * t * t - 6 * t * t + 4) / 6;
  n[0][2] = (-3 * t * t * t + 3 * t * t + 3 * t + 1) / 6;
  n[0][3] = t * t * t / 6;
  n[1][0] = -s * s / 2;
  n[1][1] = (9 * t * t - 12 * t) / 6;
  n[1][2] = (-9 * t * t + 6 * t + 3) / 6;
  n[1][3] = t * t / 2;
  n[2][0] = s;
  n[2][1] = 3 * t - 2;
  n[2][2] = -3 * t + 1;
  n[2][3] = t;
}

/// M[d](i, j) = integral_0^1 N_i^(d) N_j^(d): 4-point Gauss-Legendre, exact for degree <= 7.
std::array<Eigen::Matrix4d, 3> span_grams() {
  const double a = std::sqrt(3.0 / 7 - 2.0 / 7 * std::sqrt(6.0 / 5)), b = std::sqrt(3.0 / 7 + 2.0 / 7 * std::sqrt(6.0 / 5));
  const double wa = (18 + std::sqrt(30.0)) / 36, wb = (18 - std::sqrt(30.0)) / 36;
  const double x[4] = {-b, -a, a, b}, w[4] = {wb, wa, wa, wb};
  std::array<Eigen::Matrix4d, 3> m;
  for (auto& g : m) g.setZero();
  for (int q = 0; q < 4; ++q) {
    double n[3][4];
    basis((x[q] + 1) / 2, n);
    for (int d = 0; d < 3; ++d)
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) m[d](i, j) += w[q] / 2 * n[d][i] * n[d][j];
  }
  return m;
}

Eigen::Matrix<double, 16, 16> kron(const Eigen::Matrix4d& U, const Eigen::Matrix4d& V) {
  // index i + 4 j with i along u: entry (i + 4j, k + 4l) = U(i, k) V(j, l)
  Eigen::Matrix<double, 16, 16> out;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 4; ++k)
        for (int l = 0; l < 4; ++l) out(i + 4 * j, k + 4 * l) = U(i, k) * V(j, l);
  return out;
}

bool smooth_regular(const SubdivLevel& L, int v) {
  const PolyMesh& m = L.mesh;
  if (m.vertex_face_count(v) != 4 || m.is_boundary_vertex(v) || L.vertex_sharpness[v] != 0.0f) return false;
  const int* c = m.vertex_corners(v);
  for (int i = 0; i < 4; ++i)
    if (m.face_size(m.corner_face(c[i])) != 4) return false;
  bool ok = true;
  for_each_vertex_edge(m, v, [&](int e, int) {
    if (L.edge_sharpness[e] != 0.0f) ok = false;
  });
  return ok;
}

/// The 4 x 4 control points of regular quad f, G[i + 4 j], f over [1,2]^2, i along its first
/// edge. Every corner of f must be smooth_regular.
std::array<int, 16> patch_points(const PolyMesh& m, int f) {
  std::array<int, 16> g{};
  auto put = [&](int k, int i, int j, int vertex) {
    for (int r = 0; r < k; ++r) {  // rotate (i, j) -> (3 - j, i), k times
      const int t = i;
      i = 3 - j;
      j = t;
    }
    g[i + 4 * j] = vertex;
  };
  for (int k = 0; k < 4; ++k) {
    const int h = m.face_begin(f) + k;
    const int t = m.twin(h);
    const int a = m.to_vertex(m.next(t)), b = m.to_vertex(m.next(m.next(t)));
    const int d = m.to_vertex(m.next(m.next(m.twin(m.next(t)))));
    put(k, 1, 1, m.corner_vertex(h));
    put(k, 1, 0, a);
    put(k, 2, 0, b);
    put(k, 0, 0, d);
  }
  return g;
}

}  // namespace

Eigen::Matrix<double, 16, 16> bicubic_energy_gram(double thin_plate, double membrane) {
  const auto m = span_grams();
  Eigen::Matrix<double, 16, 16> g = Eigen::Matrix<double, 16, 16>::Zero();
  if (thin_plate != 0) g += thin_plate * (kron(m[2], m[0]) + 2 * kron(m[1], m[1]) + kron(m[0], m[2]));
  if (membrane != 0) g += membrane * (kron(m[1], m[0]) + kron(m[0], m[1]));
  return g;
}

SparseMatrix energy_matrix(const SubdivLevel& level, const EnergyOptions& options) {
  if (options.levels < 0 || options.levels > 4) throw std::invalid_argument("energy: levels must be 0..4");
  const int k = options.levels;
  const Refinement ref = refine_uniform(level, k);
  const SubdivLevel& lk = ref.levels[k];
  const PolyMesh& mk = lk.mesh;
  // Base face of every level-k face, for the parameter scale (n-gon pieces start at level 1).
  std::vector<int> anc(level.mesh.num_faces());
  for (int f = 0; f < level.mesh.num_faces(); ++f) anc[f] = f;
  for (int t = 0; t < k; ++t) {
    const PolyMesh& mt = ref.levels[t].mesh;
    std::vector<int> next(mt.num_corners());
    for (int h = 0; h < mt.num_corners(); ++h) next[h] = anc[mt.corner_face(h)];
    anc.swap(next);
  }
  const Eigen::Matrix<double, 16, 16> g_tp = bicubic_energy_gram(options.thin_plate, 0);
  const Eigen::Matrix<double, 16, 16> g_mem = bicubic_energy_gram(0, options.membrane);
  std::vector<char> regular(mk.num_vertices());
  for (int v = 0; v < mk.num_vertices(); ++v) regular[v] = smooth_regular(lk, v);
  std::vector<Eigen::Triplet<double>> trip;
  for (int f = 0; f < mk.num_faces(); ++f) {
    if (lk.face_hole[f] || mk.face_size(f) != 4) continue;
    bool ok = true;
    for (int h = mk.face_begin(f); h < mk.face_end(f); ++h) ok = ok && regular[mk.corner_vertex(h)];
    if (!ok) continue;
    const int steps = level.mesh.face_size(anc[f]) == 4 ? k : k - 1;  // levels below ptex size
    const Eigen::Matrix<double, 16, 16> g = std::ldexp(1.0, 2 * steps) * g_tp + g_mem;
    const std::array<int, 16> p = patch_points(mk, f);
    for (int a = 0; a < 16; ++a)
      for (int b = 0; b < 16; ++b) trip.emplace_back(p[a], p[b], g(a, b));
  }
  SparseMatrix Kk(mk.num_vertices(), mk.num_vertices());
  Kk.setFromTriplets(trip.begin(), trip.end());
  if (k == 0) return Kk;
  const SparseMatrix S = fit_detail::to_sparse(ref.stencils_from_base(k));
  SparseMatrix K = SparseMatrix(S.transpose()) * Kk * S;
  K.prune(0.0);
  return K;
}

double energy(const SparseMatrix& K, const std::vector<Point3>& positions) {
  const Eigen::MatrixX3d P = fit_detail::to_matrix(positions);
  return (P.transpose() * (K * P)).trace();
}

std::vector<char> kept_vertices(const SubdivLevel& level, const KeepSet& keep) {
  const PolyMesh& m = level.mesh;
  std::vector<char> out(m.num_vertices(), 0);
  for (int v = 0; v < m.num_vertices(); ++v) {
    if (keep.boundary && m.is_boundary_vertex(v)) out[v] = 1;
    if (keep.tagged && level.vertex_sharpness[v] > 0.0f && !is_sharpened_by_tagging(m, level.options.boundary, v))
      out[v] = 1;
  }
  if (keep.creases || keep.tagged)
    for (int e = 0; e < m.num_edges(); ++e)
      if (!m.is_boundary_edge(e) && level.edge_sharpness[e] > 0.0f) out[m.edge_vertex(e, 0)] = out[m.edge_vertex(e, 1)] = 1;
  return out;
}

FairResult fair(const SubdivLevel& level, const std::vector<Point3>& start, const std::vector<Point3>& targets,
                const FairOptions& options) {
  const int n = level.mesh.num_vertices();
  if (!(options.weight > 0 && std::isfinite(options.weight)))
    throw std::invalid_argument("fairing: the weight must be a positive number");
  if (static_cast<int>(start.size()) != n || static_cast<int>(targets.size()) != n ||
      (!options.keep.empty() && static_cast<int>(options.keep.size()) != n))
    throw std::invalid_argument("fairing: one start position, target and keep flag per cage vertex");
  const SparseMatrix K = energy_matrix(level, options.energy);
  const LimitRows lr = limit_rows(level, options.polar.empty() ? nullptr : &options.polar);
  const SparseMatrix L = fit_detail::to_sparse(lr.rows);
  const SparseMatrix A = SparseMatrix(L.transpose() * L) + options.weight * K;
  const Eigen::MatrixX3d c = fit_detail::to_matrix(targets);
  const Eigen::MatrixX3d b = L.transpose() * c;
  const Eigen::MatrixX3d P0 = fit_detail::to_matrix(start);

  std::vector<int> free_index(n, -1), free_list;
  for (int v = 0; v < n; ++v)
    if (options.keep.empty() || !options.keep[v]) {
      free_index[v] = static_cast<int>(free_list.size());
      free_list.push_back(v);
    }
  const int nf = static_cast<int>(free_list.size());
  FairResult out;
  out.free = nf;
  out.kept = n - nf;
  out.positions = start;
  out.energy_before = energy(K, start);
  if (nf > 0) {
    // A_FF P_F = b_F - A_FK P_K
    std::vector<Eigen::Triplet<double>> trip;
    Eigen::MatrixX3d rhs(nf, 3);
    for (int i = 0; i < nf; ++i) rhs.row(i) = b.row(free_list[i]);
    for (int col = 0; col < A.outerSize(); ++col)
      for (SparseMatrix::InnerIterator it(A, col); it; ++it) {
        const int r = static_cast<int>(it.row()), fr = free_index[r], fc = free_index[col];
        if (fr < 0) continue;
        if (fc >= 0)
          trip.emplace_back(fr, fc, it.value());
        else
          rhs.row(fr) -= it.value() * P0.row(col);
      }
    SparseMatrix Aff(nf, nf);
    Aff.setFromTriplets(trip.begin(), trip.end());
    Eigen::SimplicialLDLT<SparseMatrix> solver(Aff);
    if (solver.info() != Eigen::Success)
      throw FitError("fairing: the system could not be factorised (is a component of the cage without "
                     "kept vertices and without limit surface?)",
                     {});
    const Eigen::MatrixX3d Pf = solver.solve(rhs);
    const double rnorm = (Aff * Pf - rhs).norm(), bnorm = rhs.norm();
    if (!(rnorm <= 1e-8 * std::max(bnorm, 1e-300)) || !Pf.allFinite()) {
      std::ostringstream os;
      os << "fairing: the solve left a relative residual of " << rnorm / std::max(bnorm, 1e-300);
      throw FitError(os.str(), {});
    }
    for (int i = 0; i < nf; ++i)
      for (int k = 0; k < 3; ++k) out.positions[free_list[i]][k] = Pf(i, k);
  }
  out.energy_after = energy(K, out.positions);
  const Eigen::MatrixX3d r = L * fit_detail::to_matrix(out.positions) - c;
  out.data_after = r.squaredNorm();
  std::vector<Point3> lim;
  lr.rows.apply(out.positions, lim);
  std::vector<char> skip(static_cast<size_t>(n), 0);
  for (int v : lr.no_surface) skip[static_cast<size_t>(v)] = 1;
  out.residual = field_stats(lim, targets, &skip);
  out.displacement = field_stats(out.positions, start);
  return out;
}

SparseMatrix grid_thin_plate_matrix(int nu, int nv) {
  if (nu < 1 || nv < 1) throw std::invalid_argument("grid_thin_plate_matrix: empty grid");
  auto id = [nu](int i, int j) { return i + nu * j; };
  std::vector<Eigen::Triplet<double>> duu, dvv, duv;
  int r = 0;
  for (int j = 0; j < nv; ++j)
    for (int i = 1; i + 1 < nu; ++i, ++r) {
      duu.emplace_back(r, id(i - 1, j), 1);
      duu.emplace_back(r, id(i, j), -2);
      duu.emplace_back(r, id(i + 1, j), 1);
    }
  SparseMatrix Duu(r, nu * nv);
  Duu.setFromTriplets(duu.begin(), duu.end());
  r = 0;
  for (int j = 1; j + 1 < nv; ++j)
    for (int i = 0; i < nu; ++i, ++r) {
      dvv.emplace_back(r, id(i, j - 1), 1);
      dvv.emplace_back(r, id(i, j), -2);
      dvv.emplace_back(r, id(i, j + 1), 1);
    }
  SparseMatrix Dvv(r, nu * nv);
  Dvv.setFromTriplets(dvv.begin(), dvv.end());
  r = 0;
  for (int j = 0; j + 1 < nv; ++j)
    for (int i = 0; i + 1 < nu; ++i, ++r) {
      duv.emplace_back(r, id(i, j), 1);
      duv.emplace_back(r, id(i + 1, j), -1);
      duv.emplace_back(r, id(i, j + 1), -1);
      duv.emplace_back(r, id(i + 1, j + 1), 1);
    }
  SparseMatrix Duv(r, nu * nv);
  Duv.setFromTriplets(duv.begin(), duv.end());
  return SparseMatrix(Duu.transpose() * Duu) + 2 * SparseMatrix(Duv.transpose() * Duv) +
         SparseMatrix(Dvv.transpose() * Dvv);
}

}  // namespace subd2nurbs
