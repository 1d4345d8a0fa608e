#include "core/limit/stam_eigen.h"

#include <Eigen/Sparse>

#include <cmath>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/refine/refiner.h"
#include "core/util/constants.h"

namespace subd2nurbs {

namespace {

constexpr int kR = 4;  // quads per sector side in the synthetic mesh (level-1 points need <= 2)

/// Synthetic mesh: an interior vertex of valence n, each sector a kR x kR grid of quads.
struct SectorMesh {
  int n;
  MeshInput input;
  std::vector<int> ray;  // ray[r * (kR+1) + i]: i steps along ray r (i >= 1); ray[.. + 0] = 0
  std::vector<int> in;   // in[(s * kR + (i-1)) * kR + (j-1)]: interior point (i, j >= 1) of sector s

  explicit SectorMesh(int valence) : n(valence) {
    int next = 1;  // vertex 0 is the extraordinary vertex
    ray.assign(static_cast<size_t>(n) * (kR + 1), 0);
    for (int r = 0; r < n; ++r)
      for (int i = 1; i <= kR; ++i) ray[r * (kR + 1) + i] = next++;
    in.assign(static_cast<size_t>(n) * kR * kR, 0);
    for (int s = 0; s < n; ++s)
      for (int i = 1; i <= kR; ++i)
        for (int j = 1; j <= kR; ++j) in[(s * kR + (i - 1)) * kR + (j - 1)] = next++;
    input.positions.assign(next, {0.0, 0.0, 0.0});
    for (int s = 0; s < n; ++s)
      for (int a = 0; a < kR; ++a)
        for (int b = 0; b < kR; ++b) {  // face index s*kR*kR + a*kR + b
          input.face_sizes.push_back(4);
          for (int q : {grid(s, a, b), grid(s, a + 1, b), grid(s, a + 1, b + 1), grid(s, a, b + 1)})
            input.face_indices.push_back(q);
        }
  }
  /// G_s[i][j], 0 <= i, j <= kR.
  int grid(int s, int i, int j) const {
    s = ((s % n) + n) % n;
    if (i == 0 && j == 0) return 0;
    if (j == 0) return ray[s * (kR + 1) + i];
    if (i == 0) return ray[((s + 1) % n) * (kR + 1) + j];
    return in[(s * kR + (i - 1)) * kR + (j - 1)];
  }
  int face(int s, int a, int b) const { return ((((s % n) + n) % n) * kR + a) * kR + b; }
};

/// Sector coordinates with one negative index mapped into the neighbouring sector
/// (docs/math.md 0.2): (i, -1) in s is G_{s-1}[1][i], (-1, j) in s is G_{s+1}[j][1].
void normalise(int n, int& s, int& i, int& j) {
  if (j < 0) { s = s - 1; j = i; i = 1; }
  else if (i < 0) { s = s + 1; i = j; j = 1; }
  s = ((s % n) + n) % n;
}

/// Vertex id of sector point (i, j) (level-0 units) of the synthetic base mesh.
int base_id(const SectorMesh& sm, int s, int i, int j) {
  normalise(sm.n, s, i, j);
  return sm.grid(s, i, j);
}

/// Vertex id of sector point (I, J) (level-1 units) after one refine_once of the synthetic mesh.
int child_id(const SectorMesh& sm, const PolyMesh& m, int s, int I, int J) {
  normalise(sm.n, s, I, J);
  const bool io = I % 2 != 0, jo = J % 2 != 0;
  if (!io && !jo) return child_of_vertex(m, sm.grid(s, I / 2, J / 2));
  if (io && jo) return child_of_face(m, sm.face(s, (I - 1) / 2, (J - 1) / 2));
  int a, b;
  if (io) {
    a = sm.grid(s, (I - 1) / 2, J / 2);
    b = sm.grid(s, (I + 1) / 2, J / 2);
  } else {
    a = sm.grid(s, I / 2, (J - 1) / 2);
    b = sm.grid(s, I / 2, (J + 1) / 2);
  }
  const int e = m.find_edge(a, b);
  if (e < 0) throw std::logic_error("stam_eigen: synthetic edge missing");
  return child_of_edge(m, e);
}

const int kOuter[7][2] = {{2, -1}, {2, 0}, {2, 1}, {2, 2}, {1, 2}, {0, 2}, {-1, 2}};

/// Configuration point c (0..2n+7) in sector-0 coordinates.
void config_coords(int n, int c, int& s, int& i, int& j) {
  s = 0;
  if (c == 0) { i = 0; j = 0; return; }
  if (c <= n) { s = c - 1; i = 1; j = 0; return; }          // e_r = G_r[1][0]
  if (c <= 2 * n) { s = c - 1 - n; i = 1; j = 1; return; }  // d_r = G_r[1][1]
  i = kOuter[c - 2 * n - 1][0];
  j = kOuter[c - 2 * n - 1][1];
}

std::shared_ptr<const StamEigen> build(int n) {
  auto out = std::make_shared<StamEigen>();
  StamEigen& E = *out;
  E.n = n;
  E.K = 2 * n + 1;
  const int K = E.K, C = K + 7;

  SectorMesh sm(n);
  const SubdivLevel base = SubdivLevel::from_input(sm.input);
  const RefinementStep step = refine_once(base);
  const PolyMesh& pm = base.mesh;

  std::map<int, int> column;  // base vertex id -> configuration index
  for (int c = 0; c < C; ++c) {
    int s, i, j;
    config_coords(n, c, s, i, j);
    column[base_id(sm, s, i, j)] = c;
  }
  if (static_cast<int>(column.size()) != C) throw std::logic_error("stam_eigen: configuration not distinct");
  auto row_of = [&](int child) {
    Eigen::RowVectorXd r = Eigen::RowVectorXd::Zero(C);
    const StencilTable& t = step.stencils;
    for (int k = t.offsets[child]; k < t.offsets[child + 1]; ++k) {
      auto it = column.find(t.indices[k]);
      if (it == column.end()) {
        if (t.weights[k] != 0.0) throw std::logic_error("stam_eigen: stencil leaves the configuration");
        continue;
      }
      r(it->second) += t.weights[k];
    }
    return r;
  };
  E.A.resize(C, C);
  for (int c = 0; c < C; ++c) {
    int s, i, j;
    config_coords(n, c, s, i, j);
    E.A.row(c) = row_of(child_id(sm, pm, s, i, j));
  }
  E.S = E.A.topLeftCorner(K, K);
  E.S12 = E.A.bottomRightCorner(7, 7);
  const Eigen::MatrixXd S11 = E.A.bottomLeftCorner(7, K);

  // Real Fourier subspaces of S (docs/math.md 9.2). Ring index: v 0, e_r 1+r, d_r 1+n+r.
  std::vector<Eigen::MatrixXd> bases;
  {
    Eigen::MatrixXd Q = Eigen::MatrixXd::Zero(K, 3);
    Q(0, 0) = 1;
    for (int r = 0; r < n; ++r) { Q(1 + r, 1) = 1; Q(1 + n + r, 2) = 1; }
    bases.push_back(Q);
  }
  for (int l = 1; 2 * l <= n; ++l) {
    for (int kind = 0; kind < 2; ++kind) {  // cos, sin
      Eigen::MatrixXd Q = Eigen::MatrixXd::Zero(K, 2);
      for (int r = 0; r < n; ++r) {
        const double te = 2 * kPi * l * r / n, td = 2 * kPi * l * (r + 0.5) / n;
        Q(1 + r, 0) = kind == 0 ? std::cos(te) : std::sin(te);
        Q(1 + n + r, 1) = kind == 0 ? std::cos(td) : std::sin(td);
      }
      if (2 * l == n) {  // frequency n/2: cos has no d part, sin no e part: one vector each
        Eigen::MatrixXd q(K, 1);
        q.col(0) = kind == 0 ? Q.col(0) : Q.col(1);
        bases.push_back(q);
      } else {
        bases.push_back(Q);
      }
    }
  }
  // S has at most 9 entries per row. Above kDenseValence its products are taken as a sparse
  // matrix's and V is inverted block by block, so that the decomposition is O(K^2) (dense
  // products and a dense inverse are O(K^3): 40 s at valence 1000). Up to it the dense
  // computation is kept: the same to rounding, and bit for bit what every conversion made so
  // far (the mesh path's fit amplifies a change in the last bit into another cage).
  const bool dense = n <= kDenseValence;
  const Eigen::SparseMatrix<double> S_sparse = E.S.sparseView();
  E.V = Eigen::MatrixXd::Zero(K, K);
  E.Vinv = Eigen::MatrixXd::Zero(K, K);
  E.lambda = Eigen::VectorXd::Zero(K);
  int col = 0;
  for (const Eigen::MatrixXd& Q0 : bases) {
    // Orthonormal columns (the Fourier vectors of one block are orthogonal already).
    Eigen::MatrixXd Q = Q0;
    for (int c = 0; c < Q.cols(); ++c) Q.col(c).normalize();
    const Eigen::MatrixXd SQ = dense ? Eigen::MatrixXd(E.S * Q) : Eigen::MatrixXd(S_sparse * Q);
    const Eigen::MatrixXd B =
        dense ? Eigen::MatrixXd(Q.transpose() * E.S * Q) : Eigen::MatrixXd(Q.transpose() * SQ);
    const double inv_res = (SQ - Q * B).cwiseAbs().maxCoeff();
    if (inv_res > 1e-12) throw std::runtime_error("stam_eigen: Fourier subspace not invariant");
    Eigen::EigenSolver<Eigen::MatrixXd> es(B);
    if (es.info() != Eigen::Success) throw std::runtime_error("stam_eigen: block eigen-solver failed");
    Eigen::MatrixXd Y(B.rows(), B.cols());  // the block's unit eigenvectors in Q's coordinates
    for (int c = 0; c < B.cols(); ++c) {
      if (std::abs(es.eigenvalues()(c).imag()) > 1e-12)
        throw std::runtime_error("stam_eigen: complex eigenvalue");
      E.lambda(col + c) = es.eigenvalues()(c).real();
      Eigen::VectorXd x = Q * es.eigenvectors().col(c).real();
      const double length = x.norm();
      E.V.col(col + c) = x / length;
      Y.col(c) = es.eigenvectors().col(c).real() / length;
    }
    if (!dense) {
      // The blocks' Q are orthonormal to each other and together span R^K, so V = [Q_b Y_b]
      // has the inverse whose rows of block b are Y_b^-1 Q_b^T.
      Eigen::FullPivLU<Eigen::MatrixXd> lu(Y);
      if (!lu.isInvertible()) throw std::runtime_error("stam_eigen: eigenvectors are dependent");
      E.Vinv.middleRows(col, Y.cols()) = lu.inverse() * Q.transpose();
    }
    col += static_cast<int>(Y.cols());
  }
  if (col != K) throw std::logic_error("stam_eigen: subspace dimensions do not add up");
  // Dominant eigenvalue 1 first (the constant vector) so that callers can rely on it.
  int one = 0;
  for (int c = 0; c < K; ++c)
    if (std::abs(E.lambda(c) - 1.0) < std::abs(E.lambda(one) - 1.0)) one = c;
  if (one != 0) {
    std::swap(E.lambda(0), E.lambda(one));
    E.V.col(0).swap(E.V.col(one));
    E.Vinv.row(0).swap(E.Vinv.row(one));
  }
  if (dense) {
    Eigen::FullPivLU<Eigen::MatrixXd> lu(E.V);
    if (!lu.isInvertible()) throw std::runtime_error("stam_eigen: eigenvectors are dependent");
    E.Vinv = lu.inverse();
  }
  E.eigen_residual = (S_sparse * E.V - E.V * E.lambda.asDiagonal()).cwiseAbs().maxCoeff();
  if (E.eigen_residual > 1e-12) throw std::runtime_error("stam_eigen: residual check failed");
  E.W = S11 * E.V;
  E.limit_weights = ring_limit_weights(n, -1);  // in closed form above kDenseValence

  // Tiles of the next level: 16 points each, rows over the level-0 configuration.
  const int tile_origin[3][2] = {{0, -1}, {0, 0}, {-1, 0}};  // k = 1, 2, 3: grid of P[0][0]
  for (int k = 0; k < 3; ++k) {
    Eigen::MatrixXd T(16, C);
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        T.row(4 * a + b) = row_of(child_id(sm, pm, 0, tile_origin[k][0] + a, tile_origin[k][1] + b));
    E.tile_ring_V[k] = T.leftCols(K) * E.V;
    E.tile_outer[k] = T.rightCols(7);
  }
  return out;
}

}  // namespace

std::shared_ptr<const StamEigen> stam_eigen(int n) {
  if (n < 3 || n > 1024)
    throw std::invalid_argument("stam_eigen: valence " + std::to_string(n) + " outside 3..1024");
  static std::mutex mutex;
  static std::map<int, std::shared_ptr<const StamEigen>> cache;
  {
    std::lock_guard<std::mutex> lock(mutex);
    auto it = cache.find(n);
    if (it != cache.end()) return it->second;
  }
  std::shared_ptr<const StamEigen> e = build(n);  // outside the lock; a racing duplicate is harmless
  std::lock_guard<std::mutex> lock(mutex);
  return cache.emplace(n, std::move(e)).first->second;
}

}  // namespace subd2nurbs
