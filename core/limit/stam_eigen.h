// Eigenstructure of the Catmull-Clark subdivision matrix around an interior extraordinary
// vertex of valence n surrounded by quads (Stam 1998; docs/math.md section 9), per valence.
//
// Configuration (docs/math.md 9.1), in sector-s coordinates (i along edge ray s, j along ray s+1):
//   ring  K = 2n+1 points: v, e_0..e_{n-1}, d_0..d_{n-1}, rotated so that the patch's sector is 0
//   outer 7 points: (2,-1), (2,0), (2,1), (2,2), (1,2), (0,2), (-1,2)
// One CC step maps the 2n+8 points to the same configuration one level finer:
// A = [[S, 0], [S11, S12]]. The three regular tiles of the next level take their 16 points
// from A-bar (2n+17 rows); here they are stored per tile as 16 x (2n+8) matrices.
//
// Robustness: the ring matrix S is diagonalised block by block in its real Fourier subspaces
// (docs/math.md 9.2: frequency 0 is a 3x3 block, every other frequency 2x2 blocks on cos / sin
// vectors), so no general non-symmetric eigen-solver touches a matrix with repeated eigenvalues.
// The outer block S12 (eigenvalues 1/8 .. 1/64) is not diagonalised: for n = 8, 12, ... S has
// the eigenvalue 1/8 too (frequency n/4), a double root shared with S12. The full A turns out
// to be diagonalisable all the same (StamEigen.FullMatrixIsWellConditioned: cond(V_A) <= 265 for
// n = 3..16, as docs/math.md 9.2 says), but nothing here relies on it: the outer points are carried
// by the exact recurrence o_{k+1} = S11 V Lambda^k c^ + S12 o_k.
//
// The matrices are not typed in: they are read off one step of our own refiner (refine_once,
// identical to OpenSubdiv) on a synthetic mesh, so they follow the refiner's rules exactly.
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Dense>

namespace subd2nurbs {

struct StamEigen {
  int n = 0;  ///< valence
  int K = 0;  ///< 2n + 1 ring points
  Eigen::MatrixXd A;        ///< (2n+8) x (2n+8) subdivision matrix of the configuration
  Eigen::MatrixXd S;        ///< ring block of A
  Eigen::VectorXd lambda;   ///< eigenvalues of S (real), lambda(0) = 1
  Eigen::MatrixXd V;        ///< right eigenvectors of S (columns)
  Eigen::MatrixXd Vinv;     ///< inverse of V
  Eigen::MatrixXd W;        ///< S11 * V (7 x K)
  Eigen::MatrixXd S12;      ///< 7 x 7
  /// Tiles k = 1 (quad (1,0)), 2 (quad (1,1)), 3 (quad (0,1)) of the next level: the 16
  /// B-spline points P[a][b] (row 4a+b, a along i) from the configuration: ring part already
  /// multiplied by V (16 x K), outer part (16 x 7).
  Eigen::MatrixXd tile_ring_V[3];
  Eigen::MatrixXd tile_outer[3];
  std::vector<double> limit_weights;  ///< limit position mask over the ring (ring_limit_weights)
  double eigen_residual = 0;  ///< max |S V - V Lambda|, checked at construction
};

/// Cached per valence (3 <= n <= 1024); thread-safe, computed once.
/// \throw std::invalid_argument for an unsupported valence, std::runtime_error if the
/// decomposition fails its own residual check.
std::shared_ptr<const StamEigen> stam_eigen(int n);

}  // namespace subd2nurbs
