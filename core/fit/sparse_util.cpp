#include "core/fit/sparse_util.h"

#include <Eigen/OrderingMethods>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>
#include <stdexcept>

namespace subd2nurbs::fit_detail {

namespace {

Eigen::VectorXd start_vector(int n) {
  // Deterministic, not aligned with any symmetry of a mesh.
  Eigen::VectorXd x(n);
  for (int i = 0; i < n; ++i) x[i] = 1.0 + 0.5 * std::sin(1.7 * i + 0.3);
  return x.normalized();
}

}  // namespace


SparseMatrix to_sparse(const StencilTable& t) {
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(t.weights.size());
  for (int r = 0; r < t.num_rows(); ++r)
    for (int k = t.offsets[r]; k < t.offsets[r + 1]; ++k) trip.emplace_back(r, t.indices[k], t.weights[k]);
  SparseMatrix m(t.num_rows(), t.num_sources);
  m.setFromTriplets(trip.begin(), trip.end());
  return m;
}

Eigen::MatrixX3d to_matrix(const std::vector<Point3>& p) {
  Eigen::MatrixX3d m(static_cast<Eigen::Index>(p.size()), 3);
  for (size_t i = 0; i < p.size(); ++i)
    for (int c = 0; c < 3; ++c) m(static_cast<Eigen::Index>(i), c) = p[i][c];
  return m;
}

std::vector<Point3> to_points(const Eigen::MatrixX3d& m) {
  std::vector<Point3> p(static_cast<size_t>(m.rows()));
  for (size_t i = 0; i < p.size(); ++i)
    for (int c = 0; c < 3; ++c) p[i][c] = m(static_cast<Eigen::Index>(i), c);
  return p;
}

double bbox_diagonal(const std::vector<Point3>& p) {
  if (p.empty()) return 0;
  Point3 lo = p[0], hi = p[0];
  for (const Point3& q : p)
    for (int c = 0; c < 3; ++c) {
      lo[c] = std::min(lo[c], q[c]);
      hi[c] = std::max(hi[c], q[c]);
    }
  return std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                   (hi[2] - lo[2]) * (hi[2] - lo[2]));
}

std::vector<int> largest_entries(const Eigen::VectorXd& x, int count) {
  std::vector<int> idx(static_cast<size_t>(x.size()));
  std::iota(idx.begin(), idx.end(), 0);
  const int k = std::min<int>(count, static_cast<int>(idx.size()));
  std::partial_sort(idx.begin(), idx.begin() + k, idx.end(),
                    [&](int a, int b) { return std::abs(x[a]) > std::abs(x[b]); });
  idx.resize(static_cast<size_t>(k));
  return idx;
}

std::string vertex_list(const std::vector<int>& v) {
  std::ostringstream os;
  for (size_t i = 0; i < v.size(); ++i) os << (i ? ", " : "") << v[i];
  return os.str();
}


void BlockLDLT3::analyze(int n, const std::vector<int>& row, const std::vector<int>& col) {
  if (n < 0 || row.size() != col.size()) throw std::invalid_argument("BlockLDLT3::analyze: bad pattern");
  n_ = n;
  const std::size_t m = row.size();
  std::vector<char> has_diagonal(static_cast<std::size_t>(n), 0);
  for (std::size_t e = 0; e < m; ++e) {
    if (row[e] < 0 || col[e] >= n || row[e] > col[e])
      throw std::invalid_argument("BlockLDLT3::analyze: a block outside the upper triangle");
    if (row[e] == col[e]) has_diagonal[static_cast<std::size_t>(row[e])] = 1;
  }
  for (char d : has_diagonal)
    if (!d) throw std::invalid_argument("BlockLDLT3::analyze: a diagonal block is missing");

  // The fill-reducing ordering: AMD of the block pattern (both triangles).
  {
    std::vector<Eigen::Triplet<double>> trip;
    trip.reserve(2 * m);
    for (std::size_t e = 0; e < m; ++e) {
      trip.emplace_back(row[e], col[e], 1.0);
      if (row[e] != col[e]) trip.emplace_back(col[e], row[e], 1.0);
    }
    SparseMatrix pattern(n, n);
    pattern.setFromTriplets(trip.begin(), trip.end());
    Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> p;
    Eigen::AMDOrdering<int> amd;
    amd(pattern, p);
    perm_.assign(p.indices().data(), p.indices().data() + n);
  }
  inv_.assign(static_cast<std::size_t>(n), -1);
  for (int k = 0; k < n; ++k) inv_[static_cast<std::size_t>(perm_[static_cast<std::size_t>(k)])] = k;

  // The permuted upper triangle, by column.
  ucol_.assign(static_cast<std::size_t>(n) + 1, 0);
  for (std::size_t e = 0; e < m; ++e) ++ucol_[static_cast<std::size_t>(std::max(inv_[row[e]], inv_[col[e]])) + 1];
  for (int k = 0; k < n; ++k) ucol_[k + 1] += ucol_[k];
  urow_.resize(m);
  usrc_.resize(m);
  ukind_.resize(m);
  std::vector<int> next(ucol_.begin(), ucol_.end() - 1);
  for (std::size_t e = 0; e < m; ++e) {
    const int a = inv_[row[e]], b = inv_[col[e]];
    const int at = next[static_cast<std::size_t>(std::max(a, b))]++;
    urow_[at] = std::min(a, b);
    usrc_[at] = static_cast<int>(e);
    ukind_[at] = a == b ? 2 : a < b ? 0 : 1;
  }

  // The elimination tree and L's column counts (LDL's symbolic step).
  parent_.assign(static_cast<std::size_t>(n), -1);
  lnz_.assign(static_cast<std::size_t>(n), 0);
  flag_.assign(static_cast<std::size_t>(n), -1);
  for (int k = 0; k < n; ++k) {
    flag_[k] = k;
    for (int p = ucol_[k]; p < ucol_[k + 1]; ++p)
      for (int i = urow_[p]; flag_[i] != k; i = parent_[i]) {
        if (parent_[i] == -1) parent_[i] = k;
        ++lnz_[i];
        flag_[i] = k;
      }
  }
  lp_.assign(static_cast<std::size_t>(n) + 1, 0);
  for (int k = 0; k < n; ++k) lp_[k + 1] = lp_[k] + lnz_[k];
  li_.assign(static_cast<std::size_t>(lp_[n]), 0);
  lx_.assign(9 * static_cast<std::size_t>(lp_[n]), 0.0);
  dinv_.assign(9 * static_cast<std::size_t>(n), 0.0);
  y_.assign(9 * static_cast<std::size_t>(n), 0.0);
  pattern_.assign(static_cast<std::size_t>(n), 0);
}

bool BlockLDLT3::factorize(const double* values) {
  using M3 = Eigen::Matrix3d;
  using Map = Eigen::Map<M3>;
  using CMap = Eigen::Map<const M3>;
  const int n = n_;
  std::fill(flag_.begin(), flag_.end(), -1);
  std::fill(lnz_.begin(), lnz_.end(), 0);
  double* Y = y_.data();
  for (int k = 0; k < n; ++k) {
    // Column k of the upper triangle scattered into Y, and the rows of L's row k (the reach of
    // its entries in the elimination tree) in topological order at pattern_[top..n).
    int top = n;
    flag_[k] = k;
    for (int p = ucol_[k]; p < ucol_[k + 1]; ++p) {
      int i = urow_[p];
      const double* v = values + 9 * static_cast<std::size_t>(usrc_[p]);
      double* y = Y + 9 * static_cast<std::size_t>(i);
      // Y is column-major: y[r + 3 c] is the entry (3 i + r, 3 k + c).
      switch (ukind_[p]) {
        case 0:
          for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) y[r + 3 * c] += v[3 * r + c];
          break;
        case 1:  // the stored block is (k, i): its transpose, i.e. its row-major values as column-major
          for (int q = 0; q < 9; ++q) y[q] += v[q];
          break;
        default:
          for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) y[r + 3 * c] += v[3 * std::min(r, c) + std::max(r, c)];
      }
      int len = 0;
      for (; flag_[i] != k; i = parent_[i]) {
        pattern_[len++] = i;
        flag_[i] = k;
      }
      while (len > 0) pattern_[--top] = pattern_[--len];
    }
    M3 d = Map(Y + 9 * static_cast<std::size_t>(k));
    Map(Y + 9 * static_cast<std::size_t>(k)).setZero();
    for (; top < n; ++top) {
      const int i = pattern_[top];
      const M3 yi = Map(Y + 9 * static_cast<std::size_t>(i));
      Map(Y + 9 * static_cast<std::size_t>(i)).setZero();
      const int p2 = lp_[i] + lnz_[i];
      for (int p = lp_[i]; p < p2; ++p)
        Map(Y + 9 * static_cast<std::size_t>(li_[p])).noalias() -= CMap(&lx_[9 * static_cast<std::size_t>(p)]) * yi;
      const M3 lki = yi.transpose() * CMap(&dinv_[9 * static_cast<std::size_t>(i)]);
      d.noalias() -= lki * yi;
      li_[p2] = k;
      Map lkp(&lx_[9 * static_cast<std::size_t>(p2)]);
      lkp = lki;
      ++lnz_[i];
    }
    d = 0.5 * (d + d.transpose()).eval();
    const double det = d.determinant();
    if (!(det != 0) || !std::isfinite(det)) return false;
    const M3 dinv = d.inverse();
    if (!dinv.allFinite()) return false;
    Map dk(&dinv_[9 * static_cast<std::size_t>(k)]);
    dk = dinv;
  }
  return true;
}

void BlockLDLT3::solve(const double* b, double* x) const {
  using V3 = Eigen::Vector3d;
  using CMap = Eigen::Map<const Eigen::Matrix3d>;
  const int n = n_;
  z_.resize(3 * static_cast<std::size_t>(n));
  auto z = [&](int k) { return Eigen::Map<V3>(&z_[3 * static_cast<std::size_t>(k)]); };
  for (int k = 0; k < n; ++k) z(k) = Eigen::Map<const V3>(b + 3 * static_cast<std::size_t>(perm_[k]));
  for (int j = 0; j < n; ++j) {
    const V3 zj = z(j);
    for (int p = lp_[j]; p < lp_[j + 1]; ++p) z(li_[p]).noalias() -= CMap(&lx_[9 * static_cast<std::size_t>(p)]) * zj;
  }
  for (int j = 0; j < n; ++j) z(j) = (CMap(&dinv_[9 * static_cast<std::size_t>(j)]) * z(j)).eval();
  for (int j = n - 1; j >= 0; --j) {
    V3 s = z(j);
    for (int p = lp_[j]; p < lp_[j + 1]; ++p)
      s.noalias() -= CMap(&lx_[9 * static_cast<std::size_t>(p)]).transpose() * z(li_[p]);
    z(j) = s;
  }
  for (int k = 0; k < n; ++k) Eigen::Map<V3>(x + 3 * static_cast<std::size_t>(perm_[k])) = z(k);
}

Eigen::VectorXd inverse_iteration(SparseLUSolver& lu, int n, int iterations) {
  Eigen::VectorXd x = start_vector(n);
  for (int it = 0; it < iterations; ++it) {
    Eigen::VectorXd y = lu.transpose().solve(x);
    x = lu.solve(y);
    const double nx = x.norm();
    if (!(nx > 0) || !std::isfinite(nx)) break;
    x /= nx;
  }
  return x;
}

double condition_estimate(const SparseMatrix& L, SparseLUSolver& lu) {
  const int n = static_cast<int>(L.cols());
  if (n == 0) return 1;
  Eigen::VectorXd x = start_vector(n);
  double smax = 0;
  for (int it = 0; it < 20; ++it) {
    Eigen::VectorXd y = L.transpose() * (L * x);
    smax = std::sqrt(y.norm());
    x = y / y.norm();
  }
  x = inverse_iteration(lu, n);
  const double smin = (L * x).norm();
  return smin > 0 ? smax / smin : std::numeric_limits<double>::infinity();
}

Eigen::VectorXd smallest_singular_direction_dense_fallback(const SparseMatrix& L) {
  const int n = static_cast<int>(L.cols());
  if (n <= 4000) {
    Eigen::MatrixXd d(L);
    Eigen::BDCSVD<Eigen::MatrixXd> svd(d, Eigen::ComputeFullV);
    return svd.matrixV().col(n - 1);
  }
  // sigma_max^2 I - L^T L has the smallest singular direction as its dominant eigenvector.
  Eigen::VectorXd x = start_vector(n);
  double s2 = 0;
  for (int it = 0; it < 30; ++it) {
    Eigen::VectorXd y = L.transpose() * (L * x);
    s2 = y.norm();
    x = y / s2;
  }
  x = start_vector(n);
  for (int it = 0; it < 500; ++it) {
    Eigen::VectorXd y = 1.01 * s2 * x - L.transpose() * (L * x);
    x = y.normalized();
  }
  return x;
}

}  // namespace subd2nurbs::fit_detail
