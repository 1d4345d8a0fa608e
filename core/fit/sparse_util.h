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

/// Sparse LDL^T factorisation of a symmetric matrix made of 3 x 3 blocks (n block rows and
/// columns, unknowns interleaved: 3 v + c), with D block diagonal: the up-looking algorithm of
/// T. A. Davis' LDL, each entry a dense 3 x 3 block, so that one index lookup serves 27
/// multiply-adds (the shape fit's normal equations couple the three coordinates of every pair of
/// vertices in one face's support). The fill-reducing ordering (AMD of the block pattern) and
/// the symbolic factorisation are made once by analyze(); factorize() may be called many times
/// with new values on the same pattern.
class BlockLDLT3 {
 public:
  /// The block pattern: entry e is the block (row[e], col[e]) with row[e] <= col[e] (the upper
  /// triangle; every diagonal block listed, each block once). \throw std::invalid_argument
  void analyze(int n, const std::vector<int>& row, const std::vector<int>& col);
  /// Factorises the matrix whose upper blocks are `values` (9 per entry of analyze's pattern,
  /// each row-major: values[9 e + 3 r + c] is the entry (3 row[e] + r, 3 col[e] + c); a diagonal
  /// block is read as symmetric from its upper triangle). False when a pivot block is singular
  /// or the factor not finite.
  bool factorize(const double* values);
  /// Solves A x = b (3 n each, interleaved: 3 v + c) with the last factorisation.
  void solve(const double* b, double* x) const;
  int size() const { return n_; }
  /// Blocks of L below the diagonal (the fill).
  std::size_t factor_blocks() const { return li_.size(); }

 private:
  int n_ = 0;
  std::vector<int> perm_, inv_;           ///< perm_[new] = old, inv_[old] = new
  std::vector<int> ucol_, urow_, usrc_;   ///< permuted upper pattern (CSC) and each one's entry
  std::vector<char> ukind_;               ///< 0 as stored, 1 transposed, 2 diagonal (symmetric)
  std::vector<int> parent_, lp_;          ///< elimination tree, L's column starts
  std::vector<int> li_;                   ///< L's block rows
  std::vector<double> lx_, dinv_;         ///< L's blocks (9 each, column-major), D^-1 (9 each)
  std::vector<double> y_;                 ///< factorize's work: one block column
  std::vector<int> flag_, pattern_, lnz_;
  mutable std::vector<double> z_;
};

/// Unit vector x with |L x| small (the direction of the smallest singular value), by inverse
/// iteration with the factorised L: x <- L^-1 L^-T x.
Eigen::VectorXd inverse_iteration(SparseLUSolver& lu, int n, int iterations = 12);

/// Estimate of the 2-norm condition number sigma_max / sigma_min of L (power iterations).
double condition_estimate(const SparseMatrix& L, SparseLUSolver& lu);

/// For a matrix that could not be factorised: the direction of its smallest singular value
/// (dense SVD up to 4000 unknowns, else shifted power iteration on L^T L).
Eigen::VectorXd smallest_singular_direction_dense_fallback(const SparseMatrix& L);

}  // namespace subd2nurbs::fit_detail
