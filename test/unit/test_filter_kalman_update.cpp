// The ensemble-space PC update against the state-space formulas (docs/method.md §4.3, §4.4).
#include <gtest/gtest.h>

#include <random>

#include "pc_ekf/filter/kalman_update.h"

namespace pc_ekf {
namespace {

Eigen::MatrixXd randomMatrix(int r, int c, std::mt19937_64& rng) {
  std::normal_distribution<double> n;
  Eigen::MatrixXd m(r, c);
  for (int i = 0; i < r; ++i)
    for (int j = 0; j < c; ++j) m(i, j) = n(rng);
  return m;
}

Eigen::MatrixXd covarianceOf(const Eigen::MatrixXd& x) {
  const auto a = x.rightCols(x.cols() - 1);
  return a * a.transpose();
}

struct Case {
  Eigen::MatrixXd x, h, z_coeffs, p, gain;
  Eigen::VectorXd z, r;
};

Case makeCase(int channels, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  Case c;
  c.x = randomMatrix(12, 15, rng);
  c.h = randomMatrix(channels, 12, rng);
  c.z_coeffs = c.h * c.x;
  c.z = c.z_coeffs.col(0) + randomMatrix(channels, 1, rng);
  c.r = (randomMatrix(channels, 1, rng).array().square() + 0.1).matrix();
  c.p = covarianceOf(c.x);
  const Eigen::MatrixXd s = c.h * c.p * c.h.transpose() + Eigen::MatrixXd(c.r.asDiagonal());
  c.gain = c.p * c.h.transpose() * s.inverse();
  return c;
}

TEST(KalmanUpdate, SquareRootCovarianceIsIMinusKHTimesP) {
  for (int k = 1; k <= 4; ++k) {
    Case c = makeCase(k, 100 + k);
    Eigen::MatrixXd x = c.x;
    pcKalmanUpdate(x, c.z_coeffs, c.z, c.r, UpdateRule::kSquareRoot);
    const Eigen::MatrixXd expected = (Eigen::MatrixXd::Identity(12, 12) - c.gain * c.h) * c.p;
    EXPECT_LT((covarianceOf(x) - expected).cwiseAbs().maxCoeff(), 1e-12 * c.p.norm()) << k;
    const Eigen::VectorXd mean = c.x.col(0) + c.gain * (c.z - c.h * c.x.col(0));
    EXPECT_LT((x.col(0) - mean).cwiseAbs().maxCoeff(), 1e-12 * mean.norm()) << k;
  }
}

TEST(KalmanUpdate, PaperCovarianceIsJosephFormWithoutTheNoiseTerm) {
  for (int k = 1; k <= 4; ++k) {
    Case c = makeCase(k, 200 + k);
    Eigen::MatrixXd x = c.x;
    pcKalmanUpdate(x, c.z_coeffs, c.z, c.r, UpdateRule::kPaper);
    const Eigen::MatrixXd ikh = Eigen::MatrixXd::Identity(12, 12) - c.gain * c.h;
    const Eigen::MatrixXd joseph = ikh * c.p * ikh.transpose();
    const Eigen::MatrixXd alt = ikh * c.p - c.gain * c.r.asDiagonal() * c.gain.transpose();
    EXPECT_LT((covarianceOf(x) - joseph).cwiseAbs().maxCoeff(), 1e-12 * c.p.norm()) << k;
    EXPECT_LT((joseph - alt).cwiseAbs().maxCoeff(), 1e-11 * c.p.norm()) << k;
    // It removes K R K^T more than the Bayesian (I - KH)P.
    EXPECT_GT(((ikh * c.p) - covarianceOf(x)).trace(), 1e-6);
  }
}

TEST(KalmanUpdate, WoodburyEqualsDenseFormulasForManyObservations) {
  std::mt19937_64 rng(5);
  const int k = 60;  // stacked observations >> S - 1
  Eigen::MatrixXd x = randomMatrix(2, 15, rng);
  const Eigen::MatrixXd zc = randomMatrix(k, 15, rng);
  const Eigen::VectorXd z = randomMatrix(k, 1, rng);
  const Eigen::VectorXd r = (randomMatrix(k, 1, rng).array().square() + 0.5).matrix();
  for (UpdateRule rule : {UpdateRule::kPaper, UpdateRule::kSquareRoot}) {
    Eigen::MatrixXd a = x, b = x;
    const UpdateDiagnostics da = pcKalmanUpdate(a, zc, z, r, rule);
    const UpdateDiagnostics db = pcKalmanUpdateDense(b, zc, z, r, rule);
    EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-10 * b.norm()) << toString(rule);
    EXPECT_NEAR(da.nis, db.nis, 1e-10 * db.nis);
  }
}

TEST(KalmanUpdate, NisEqualsTheDenseInnovationForm) {
  Case c = makeCase(3, 9);
  Eigen::MatrixXd x = c.x;
  const UpdateDiagnostics d = pcKalmanUpdate(x, c.z_coeffs, c.z, c.r, UpdateRule::kSquareRoot);
  const Eigen::VectorXd v = c.z - c.h * c.x.col(0);
  const Eigen::MatrixXd s = c.h * c.p * c.h.transpose() + Eigen::MatrixXd(c.r.asDiagonal());
  EXPECT_NEAR(d.nis, v.dot(s.ldlt().solve(v)), 1e-10 * d.nis);
  EXPECT_EQ(d.channels, 3);
}

TEST(KalmanUpdate, NonFiniteInputLeavesTheStateUntouched) {
  Case c = makeCase(2, 3);
  Eigen::MatrixXd x = c.x;
  Eigen::VectorXd z = c.z;
  z[1] = std::numeric_limits<double>::quiet_NaN();
  const UpdateDiagnostics d = pcKalmanUpdate(x, c.z_coeffs, z, c.r, UpdateRule::kSquareRoot);
  EXPECT_FALSE(d.finite);
  EXPECT_EQ(x, c.x);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
