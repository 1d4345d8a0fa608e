#include "core/fit/interpolate.h"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <limits>
#include <cmath>
#include <numeric>
#include <sstream>

#include "core/fit/sparse_util.h"

namespace subd2nurbs {

FieldStats field_stats(const std::vector<Point3>& a, const std::vector<Point3>& b,
                       const std::vector<char>* skip) {
  FieldStats s;
  long count = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    if (skip && (*skip)[i]) continue;
    const double d = std::sqrt((a[i][0] - b[i][0]) * (a[i][0] - b[i][0]) +
                               (a[i][1] - b[i][1]) * (a[i][1] - b[i][1]) +
                               (a[i][2] - b[i][2]) * (a[i][2] - b[i][2]));
    s.mean += d;
    ++count;
    if (d > s.max || s.where < 0) {
      s.max = d;
      s.where = static_cast<int>(i);
    }
  }
  if (count) s.mean /= static_cast<double>(count);
  return s;
}


using namespace fit_detail;


InterpolationResult interpolate(const SubdivLevel& level, const std::vector<Point3>& targets,
                                const InterpolationOptions& options) {
  const int nv = level.mesh.num_vertices();
  if (static_cast<int>(targets.size()) != nv)
    throw std::invalid_argument("interpolate: one target per cage vertex is needed");
  const LimitRows lr = limit_rows(level, options.polar.empty() ? nullptr : &options.polar);
  const SparseMatrix L = to_sparse(lr.rows);
  const Eigen::MatrixX3d c = to_matrix(targets);
  const double diag = bbox_diagonal(targets);
  SparseLUSolver lu;
  lu.analyzePattern(L);
  lu.factorize(L);
  const bool factorised = lu.info() == Eigen::Success;
  const double cond = factorised ? condition_estimate(L, lu) : std::numeric_limits<double>::infinity();
  InterpolationResult out;
  Eigen::MatrixX3d P;
  if (factorised && cond <= options.max_condition) {
    P = lu.solve(c);
  } else {
    // Singular or nearly so (e.g. the checkerboard mode of a smooth cube: 9 - 3*4 + 3 = 0).
    // Name the vertices where L's near-null vector is largest, and look for the interpolating
    // cage nearest to the targets: minimum-norm displacement D with L D = c - L c, by iterated
    // Tikhonov regularisation (every update lies in the range of L^T, so no null-space
    // component is added). If the targets are not in the range of L, no cage interpolates.
    const Eigen::VectorXd x = factorised ? inverse_iteration(lu, nv) : smallest_singular_direction_dense_fallback(L);
    std::vector<int> worst = largest_entries(x, 8);
    const double xmax = std::abs(x[worst.front()]);
    worst.erase(std::remove_if(worst.begin(), worst.end(), [&](int v) { return std::abs(x[v]) < 0.25 * xmax; }),
                worst.end());
    const SparseMatrix LtL = SparseMatrix(L.transpose() * L);
    double scale = 0;
    for (int k = 0; k < LtL.outerSize(); ++k) scale = std::max(scale, LtL.coeff(k, k));
    SparseMatrix A = LtL;
    for (int k = 0; k < nv; ++k) A.coeffRef(k, k) += 1e-6 * scale;
    Eigen::SimplicialLDLT<SparseMatrix> ldlt(A);
    if (ldlt.info() != Eigen::Success)
      throw FitError("interpolation: the limit system is singular and could not be regularised; vertices involved: " +
                         vertex_list(worst),
                     worst);
    // Conjugate gradients on L^T L D = L^T r0 from D = 0, preconditioned by the regularised
    // factorisation: the iterates stay in the range of L^T (the minimum-norm solution), and the
    // preconditioned spectrum sigma^2 / (sigma^2 + eps) is clustered at 1.
    Eigen::MatrixX3d D = Eigen::MatrixX3d::Zero(nv, 3);
    const Eigen::MatrixX3d r0 = c - L * c;
    for (int col = 0; col < 3; ++col) {
      Eigen::VectorXd xk = Eigen::VectorXd::Zero(nv), best = xk;
      Eigen::VectorXd res = L.transpose() * r0.col(col);
      // Measured on the normal equations, which a least-squares solution satisfies even when
      // the targets are outside the range of L.
      double best_res = res.norm();
      const double stop_normal = 1e-15 * std::max(best_res, 1e-300);
      Eigen::VectorXd z = ldlt.solve(res);
      Eigen::VectorXd dir = z;
      double rz = res.dot(z);
      // Keep the best iterate, stop on stagnation (rounding).
      for (int it = 0, stalled = 0; it < 500 && best_res > stop_normal && stalled < 5 && rz > 0; ++it) {
        const Eigen::VectorXd Ad = L.transpose() * (L * dir);
        const double dAd = dir.dot(Ad);
        if (!(dAd > 0)) break;
        const double alpha = rz / dAd;
        xk += alpha * dir;
        res -= alpha * Ad;
        z = ldlt.solve(res);
        const double rz_new = res.dot(z);
        dir = z + (rz_new / rz) * dir;
        rz = rz_new;
        const double now = (L.transpose() * (r0.col(col) - L * xk)).norm();
        if (now < 0.5 * best_res) {
          stalled = 0;
        } else {
          ++stalled;
        }
        if (now < best_res) {
          best_res = now;
          best = xk;
        }
      }
      D.col(col) = best;
    }
    P = c + D;
    out.singular = true;
    out.null_vertices = worst;
    const Eigen::MatrixX3d r = L * P - c;
    Eigen::Index where = 0;
    const double rmax = r.rowwise().norm().maxCoeff(&where);
    if (!(rmax <= 1e-9 * std::max(diag, 1e-300))) {
      std::ostringstream os;
      os << "interpolation: no cage interpolates these points: the limit system is ";
      if (factorised)
        os << "badly conditioned (condition estimate " << cond << ")";
      else
        os << "singular";
      os
         << " near vertices " << vertex_list(worst) << ", and the closest fit misses vertex " << where << " by "
         << rmax;
      // Name where the closest fit misses (that is where the targets leave the range of L).
      const Eigen::VectorXd miss = r.rowwise().norm();
      std::vector<int> named;
      for (int v : largest_entries(miss, 8))
        if (miss[v] > 0.25 * rmax) named.push_back(v);
      os << " (misses by more than a quarter of that at vertices " << vertex_list(named)
         << "); a fair fit (least squares with a fairing weight) accepts such points";
      throw FitError(os.str(), named);
    }
  }
  out.positions = to_points(P);
  std::vector<Point3> lim;
  lr.rows.apply(out.positions, lim);
  std::vector<char> skip(static_cast<size_t>(nv), 0);
  for (int v : lr.no_surface) skip[static_cast<size_t>(v)] = 1;
  out.residual = field_stats(lim, targets, &skip);
  out.displacement = field_stats(out.positions, targets, &skip);
  out.condition = cond;
  out.polar_vertices = static_cast<int>(lr.polar_rows.size());
  out.local_rows = lr.local_rows;
  out.no_surface = lr.no_surface;
  // The solve is checked, not trusted: a residual above rounding level means trouble.
  if (!(out.residual.max <= 1e-9 * std::max(diag, 1e-300))) {
    std::ostringstream os;
    os << "interpolation: the solve left a residual of " << out.residual.max << " at vertex "
       << out.residual.where << " (bounding-box diagonal " << diag << ")";
    throw FitError(os.str(), {out.residual.where});
  }
  return out;
}

}  // namespace subd2nurbs
