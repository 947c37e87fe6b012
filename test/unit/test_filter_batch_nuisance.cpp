// The batch methods' nuisance whitening (batch_nuisance.h): W = (I + B B^T)^(-1/2)
// against a dense inverse square root, the generalised least squares it gives
// against the augmented-state one (nuisance values estimated with the
// parameters, then dropped), and the degrees of freedom it absorbs.
#include <gtest/gtest.h>

#include <random>

#include "pc_ekf/filter/batch_nuisance.h"

namespace pc_ekf {
namespace {

Eigen::MatrixXd randomMatrix(int rows, int cols, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd m(rows, cols);
  for (int i = 0; i < rows; ++i) {
    for (int j = 0; j < cols; ++j) m(i, j) = normal(rng);
  }
  return m;
}

TEST(NuisanceWhitening, IsTheInverseSquareRootOfTheMarginalCovariance) {
  const Eigen::MatrixXd u = randomMatrix(40, 4, 3);
  const Eigen::VectorXd stds = (Eigen::VectorXd(4) << 0.03, 2.0, 0.5, 1e-3).finished();
  const NuisanceWhitening w(u, stds);
  Eigen::MatrixXd m = Eigen::MatrixXd::Identity(40, 40);
  w.apply(Eigen::Ref<Eigen::MatrixXd>(m));
  const Eigen::MatrixXd b = u * stds.asDiagonal();
  const Eigen::MatrixXd sigma = Eigen::MatrixXd::Identity(40, 40) + b * b.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(sigma);
  const Eigen::MatrixXd inv_sqrt =
      eig.eigenvectors() * eig.eigenvalues().cwiseSqrt().cwiseInverse().asDiagonal() *
      eig.eigenvectors().transpose();
  EXPECT_LT((m - inv_sqrt).cwiseAbs().maxCoeff(), 1e-12);
  // The vector form is the matrix form's.
  Eigen::VectorXd x = randomMatrix(40, 1, 4).col(0);
  const Eigen::VectorXd want = inv_sqrt * x;
  w.apply(Eigen::Ref<Eigen::VectorXd>(x));
  EXPECT_LT((x - want).cwiseAbs().maxCoeff(), 1e-12);
  // absorbed = tr(B^T Sigma^-1 B) = sum s^2 / (1 + s^2).
  const double trace = (b.transpose() * sigma.inverse() * b).trace();
  EXPECT_NEAR(w.absorbed(), trace, 1e-10);
  // Two stds large against the rows' unit noise (nearly a dof each), two small.
  EXPECT_GT(w.absorbed(), 1.8);
  EXPECT_LT(w.absorbed(), 2.1);
}

// y = H theta + U n + e, e ~ N(0, I), n ~ N(0, diag(stds^2)), theta ~ N(0, I):
// the posterior of theta from the whitened rows (W H, W y, noise I) equals the
// augmented state's (theta, n) marginal.
TEST(NuisanceWhitening, GivesTheAugmentedStatesPosterior) {
  const Eigen::MatrixXd h = randomMatrix(60, 3, 5), u = randomMatrix(60, 2, 6);
  const Eigen::VectorXd y = randomMatrix(60, 1, 7).col(0);
  const Eigen::VectorXd stds = (Eigen::VectorXd(2) << 0.7, 3.0).finished();
  const NuisanceWhitening w(u, stds);
  Eigen::MatrixXd wh = h;
  Eigen::VectorXd wy = y;
  w.apply(Eigen::Ref<Eigen::MatrixXd>(wh));
  w.apply(Eigen::Ref<Eigen::VectorXd>(wy));
  const Eigen::MatrixXd info = Eigen::MatrixXd::Identity(3, 3) + wh.transpose() * wh;
  const Eigen::VectorXd mean = info.ldlt().solve(wh.transpose() * wy);
  const Eigen::MatrixXd cov = info.inverse();

  Eigen::MatrixXd a(60, 5);
  a << h, u;
  Eigen::MatrixXd prior = Eigen::MatrixXd::Zero(5, 5);
  prior.topLeftCorner(3, 3).setIdentity();
  prior(3, 3) = 1.0 / (stds[0] * stds[0]);
  prior(4, 4) = 1.0 / (stds[1] * stds[1]);
  const Eigen::MatrixXd info_a = prior + a.transpose() * a;
  const Eigen::VectorXd mean_a = info_a.ldlt().solve(a.transpose() * y);
  const Eigen::MatrixXd cov_a = info_a.inverse();
  EXPECT_LT((mean - mean_a.head(3)).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((cov - cov_a.topLeftCorner(3, 3)).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(NuisanceWhitening, NothingToWhitenLeavesTheRowsAlone) {
  const NuisanceWhitening none;
  Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(5, 0.0, 1.0);
  const Eigen::VectorXd before = x;
  none.apply(Eigen::Ref<Eigen::VectorXd>(x));
  EXPECT_EQ(x, before);
  EXPECT_EQ(none.absorbed(), 0.0);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
