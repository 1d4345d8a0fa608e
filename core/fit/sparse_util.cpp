#include "core/fit/sparse_util.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>

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
