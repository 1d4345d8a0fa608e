// The per-valence eigenstructure (core/limit/stam_eigen.h) against the closed forms of
// MATH.md 1.4 and 7.2, which are independent of how the matrices were obtained.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <thread>
#include <vector>

#include "core/limit/stam_eigen.h"
#include "core/refine/refiner.h"

using namespace subd2nurbs;

namespace {

const double kPi = std::acos(-1.0);

/// Every eigenvalue of S predicted by MATH.md 7.2, with multiplicity.
std::vector<double> predicted_spectrum(int n) {
  std::vector<double> ev = {1.0};
  const double r = std::sqrt(5.0 * n * n - 30.0 * n + 49.0);
  ev.push_back((3.0 * n - 7 + r) / (8.0 * n));
  ev.push_back((3.0 * n - 7 - r) / (8.0 * n));
  for (int l = 1; l < n; ++l) {
    const double c = std::cos(2 * kPi * l / n);
    const double q = std::sqrt((c + 1) * (c + 9));
    ev.push_back((5 + c + q) / 16);
    ev.push_back((5 + c - q) / 16);
  }
  std::sort(ev.begin(), ev.end());
  return ev;
}

/// Valences 3 .. last, and beyond kDenseValence (core/refine/refiner.h), where the
/// decomposition takes its O(n^2) path (odd and even: an even n has the one-vector block n/2).
std::vector<int> valences_up_to(int last) {
  std::vector<int> out;
  for (int n = 3; n <= last; ++n) out.push_back(n);
  for (int n : {kDenseValence + 1, kDenseValence + 2, 200}) out.push_back(n);
  return out;
}

}  // namespace

TEST(StamEigen, SpectrumMatchesTheFourierBlocks) {
  for (int n : valences_up_to(16)) {
    SCOPED_TRACE(n);
    const auto e = stam_eigen(n);
    ASSERT_EQ(e->K, 2 * n + 1);
    std::vector<double> got(e->lambda.data(), e->lambda.data() + e->K);
    std::sort(got.begin(), got.end());
    const std::vector<double> want = predicted_spectrum(n);
    ASSERT_EQ(got.size(), want.size());
    for (size_t i = 0; i < got.size(); ++i) EXPECT_NEAR(got[i], want[i], 1e-13);
    // The subdominant eigenvalue (MATH.md 1.4).
    const double c = std::cos(2 * kPi / n);
    const double sub = (5 + c + std::cos(kPi / n) * std::sqrt(2 * (9 + c))) / 16;
    EXPECT_NEAR(got[got.size() - 2], sub, 1e-13);
    EXPECT_NEAR(e->lambda(0), 1.0, 1e-14);
    EXPECT_LT(e->eigen_residual, 1e-13);
    // V is an eigenbasis and Vinv its inverse.
    const Eigen::MatrixXd I = e->V * e->Vinv;
    EXPECT_LT((I - Eigen::MatrixXd::Identity(e->K, e->K)).cwiseAbs().maxCoeff(), 1e-12);
  }
}

TEST(StamEigen, OuterBlockAndAffineRows) {
  for (int n : valences_up_to(12)) {
    SCOPED_TRACE(n);
    const auto e = stam_eigen(n);
    // S12 has eigenvalues 1/8, 1/8, 1/16, 1/16, 1/32, 1/32, 1/64 (MATH.md 7.2).
    Eigen::EigenSolver<Eigen::MatrixXd> es(e->S12);
    std::vector<double> ev;
    for (int i = 0; i < 7; ++i) {
      EXPECT_NEAR(es.eigenvalues()(i).imag(), 0.0, 1e-12);
      ev.push_back(es.eigenvalues()(i).real());
    }
    std::sort(ev.begin(), ev.end());
    const double want[7] = {1.0 / 64, 1.0 / 32, 1.0 / 32, 1.0 / 16, 1.0 / 16, 1.0 / 8, 1.0 / 8};
    for (int i = 0; i < 7; ++i) EXPECT_NEAR(ev[i], want[i], 1e-7);  // double roots: sqrt(eps)
    // Subdivision is affine: every row of A sums to 1, and the upper right block is zero.
    for (int r = 0; r < e->A.rows(); ++r) EXPECT_NEAR(e->A.row(r).sum(), 1.0, 1e-14);
    EXPECT_EQ(e->A.topRightCorner(e->K, 7).cwiseAbs().maxCoeff(), 0.0);
    // The limit weights are the left eigenvector of eigenvalue 1.
    Eigen::RowVectorXd l(e->K);
    for (int i = 0; i < e->K; ++i) l(i) = e->limit_weights[i];
    EXPECT_LT((l * e->S - l).cwiseAbs().maxCoeff(), 1e-14);
    // n = 4: the standard limit mask 16/36, 4/36, 1/36.
    if (n == 4) {
      EXPECT_NEAR(l(0), 16.0 / 36, 1e-15);
      EXPECT_NEAR(l(1), 4.0 / 36, 1e-15);
      EXPECT_NEAR(l(5), 1.0 / 36, 1e-15);
    }
  }
}

TEST(StamEigen, CacheIsSharedAcrossThreads) {
  std::vector<std::shared_ptr<const StamEigen>> got(4);
  std::vector<std::thread> threads;
  for (int i = 0; i < 4; ++i) threads.emplace_back([&, i] { got[i] = stam_eigen(17); });
  for (auto& t : threads) t.join();
  for (int i = 1; i < 4; ++i) EXPECT_EQ(got[i].get(), stam_eigen(17).get());
  EXPECT_THROW(stam_eigen(2), std::invalid_argument);
}

TEST(StamEigen, FullMatrixIsWellConditioned) {
  // MATH.md 7.2: all eigenvalues of A real, its eigenvector matrix well conditioned (80-300
  // for n <= 8). Also for n = 8, 12, 16, where S and S12 share the eigenvalue 1/8.
  for (int n = 3; n <= 16; ++n) {
    SCOPED_TRACE(n);
    const auto e = stam_eigen(n);
    Eigen::EigenSolver<Eigen::MatrixXd> es(e->A);
    ASSERT_EQ(es.info(), Eigen::Success);
    EXPECT_LT(es.eigenvalues().imag().cwiseAbs().maxCoeff(), 1e-12);
    Eigen::JacobiSVD<Eigen::MatrixXcd> svd(es.eigenvectors());
    const auto& sv = svd.singularValues();
    EXPECT_LT(sv(0) / sv(sv.size() - 1), 1000.0);
  }
}
