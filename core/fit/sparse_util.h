// Sparse-matrix helpers shared by interpolation and fairing (internal to core/fit).
#pragma once

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <Eigen/SparseLU>
#include <string>
#include <vector>

#include "core/refine/stencil_table.h"

namespace subd2nurbs::fit_detail {

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;
using SparseLUSolver = Eigen::SparseLU<SparseMatrix, Eigen::COLAMDOrdering<int>>;

SparseMatrix to_sparse(const StencilTable& t);
Eigen::MatrixX3d to_matrix(const std::vector<Point3>& p);
std::vector<Point3> to_points(const Eigen::MatrixX3d& m);
double bbox_diagonal(const std::vector<Point3>& p);
/// Indices of the `count` entries of largest magnitude, largest first.
std::vector<int> largest_entries(const Eigen::VectorXd& x, int count);
std::string vertex_list(const std::vector<int>& v);

/// Unit vector x with |L x| small (the direction of the smallest singular value), by inverse
/// iteration with the factorised L: x <- L^-1 L^-T x.
Eigen::VectorXd inverse_iteration(SparseLUSolver& lu, int n, int iterations = 12);

/// Estimate of the 2-norm condition number sigma_max / sigma_min of L (power iterations).
double condition_estimate(const SparseMatrix& L, SparseLUSolver& lu);

/// For a matrix that could not be factorised: the direction of its smallest singular value
/// (dense SVD up to 4000 unknowns, else shifted power iteration on L^T L).
Eigen::VectorXd smallest_singular_direction_dense_fallback(const SparseMatrix& L);

}  // namespace subd2nurbs::fit_detail
