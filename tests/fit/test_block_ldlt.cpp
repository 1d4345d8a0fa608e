// The block sparse LDL^T (core/fit/sparse_util.h BlockLDLT3) against a dense solve. Oracle:
// Eigen's dense LDLT of the same matrix (and the residual of the solve); the matrices are random
// symmetric positive definite 3 x 3 block matrices with the pattern of a surface mesh (a grid's
// 5 x 5 vertex neighbourhoods) plus a few long-range pairs, as the shape fit's normal equations.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>
#include <set>
#include <utility>

#include "core/fit/sparse_util.h"

namespace subd2nurbs::testing {
namespace {

using fit_detail::BlockLDLT3;

struct BlockMatrix {
  int n = 0;
  std::vector<int> row, col;
  std::vector<double> values;  // 9 per block, row-major
  Eigen::MatrixXd dense;       // the same, interleaved 3 v + c
};

/// A grid of w x h vertices; blocks between vertices at most 2 apart in both directions, and
/// `extra` random pairs. Positive definite: a sum of r^T r (x) W rows plus a small diagonal.
BlockMatrix grid_matrix(int w, int h, int extra, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  BlockMatrix m;
  m.n = w * h;
  m.dense = Eigen::MatrixXd::Zero(3 * m.n, 3 * m.n);
  // Rows: each over a 3 x 3 patch of vertices (as a sample's support), with a random SPD W.
  auto add_row = [&](const std::vector<int>& idx) {
    Eigen::Matrix3d a;
    for (int i = 0; i < 9; ++i) a(i / 3, i % 3) = u(rng);
    const Eigen::Matrix3d W = a * a.transpose();
    std::vector<double> r(idx.size());
    for (double& x : r) x = u(rng);
    for (std::size_t i = 0; i < idx.size(); ++i)
      for (std::size_t j = 0; j < idx.size(); ++j)
        m.dense.block<3, 3>(3 * idx[i], 3 * idx[j]) += r[i] * r[j] * W;
  };
  for (int y = 0; y + 2 < h; ++y)
    for (int x = 0; x + 2 < w; ++x) {
      std::vector<int> idx;
      for (int dy = 0; dy < 3; ++dy)
        for (int dx = 0; dx < 3; ++dx) idx.push_back((y + dy) * w + x + dx);
      add_row(idx);
    }
  std::uniform_int_distribution<int> vertex(0, m.n - 1);
  for (int e = 0; e < extra; ++e) add_row({vertex(rng), vertex(rng)});
  m.dense += 1e-3 * Eigen::MatrixXd::Identity(3 * m.n, 3 * m.n);
  // Blocks listed in a scrambled order (the fit's order is its hash table's).
  std::vector<std::pair<int, int>> pairs;
  for (int a = 0; a < m.n; ++a)
    for (int b = a; b < m.n; ++b)
      if (a == b || m.dense.block<3, 3>(3 * a, 3 * b).cwiseAbs().maxCoeff() > 0) pairs.emplace_back(a, b);
  std::shuffle(pairs.begin(), pairs.end(), rng);
  for (auto [a, b] : pairs) {
    m.row.push_back(a);
    m.col.push_back(b);
    for (int k = 0; k < 9; ++k) m.values.push_back(m.dense(3 * a + k / 3, 3 * b + k % 3));
  }
  return m;
}

TEST(BlockLDLT3, SolvesLikeDenseLdltOnMeshLikePatterns) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const BlockMatrix m = grid_matrix(9 + static_cast<int>(seed), 7, 5, seed);
    BlockLDLT3 ldlt;
    ldlt.analyze(m.n, m.row, m.col);
    std::mt19937 rng(seed + 100);
    std::uniform_real_distribution<double> u(-1, 1);
    Eigen::VectorXd b(3 * m.n);
    for (int i = 0; i < b.size(); ++i) b[i] = u(rng);
    const Eigen::VectorXd expected = m.dense.ldlt().solve(b);
    // Twice on one analysis: the second with the matrix scaled (new values, same pattern).
    for (double scale : {1.0, 3.5}) {
      std::vector<double> values = m.values;
      for (double& v : values) v *= scale;
      ASSERT_TRUE(ldlt.factorize(values.data()));
      Eigen::VectorXd x(3 * m.n);
      ldlt.solve(b.data(), x.data());
      EXPECT_LT((x - expected / scale).norm(), 1e-9 * expected.norm() / scale) << "seed " << seed;
      EXPECT_LT((scale * m.dense * x - b).norm(), 1e-10 * b.norm()) << "seed " << seed;
    }
    // The factor holds at least the matrix's strictly upper blocks, and no more than the dense
    // triangle's.
    EXPECT_GE(ldlt.factor_blocks(), m.row.size() - static_cast<std::size_t>(m.n));
    EXPECT_LE(ldlt.factor_blocks(), static_cast<std::size_t>(m.n) * (m.n - 1) / 2);
  }
}

TEST(BlockLDLT3, ReportsASingularMatrixAndRejectsABadPattern) {
  // Two vertices, the second's block zero: no factorisation.
  BlockLDLT3 ldlt;
  ldlt.analyze(2, {0, 0, 1}, {0, 1, 1});
  std::vector<double> values(27, 0.0);
  for (int k : {0, 4, 8}) values[static_cast<std::size_t>(k)] = 1;
  EXPECT_FALSE(ldlt.factorize(values.data()));
  EXPECT_THROW(ldlt.analyze(2, {1}, {0}), std::invalid_argument);       // below the diagonal
  EXPECT_THROW(ldlt.analyze(2, {0, 0}, {0, 1}), std::invalid_argument);  // no block (1, 1)
}

}  // namespace
}  // namespace subd2nurbs::testing
