// SerialNoise: the variance that shared noise adds to a sum of squared
// whitened residuals, against closed forms and against simulated records.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "pc_ekf/filter/serial_noise.h"

namespace pc_ekf {
namespace {

// One channel, one input: r_k = (a eps_k - b eps_{k-1}) / sqrt(a^2 + b^2 + 2 rho a b ...):
// the caller passes the whitened loadings.
double serialSum(int samples, double g, double h, double rho) {
  SerialNoise s;
  double sum = 0.0;
  for (int k = 0; k < samples; ++k) {
    sum += s.add(Eigen::MatrixXd::Constant(1, 1, g), Eigen::MatrixXd::Constant(1, 1, h),
                 Eigen::VectorXd::Constant(1, rho));
  }
  return sum;
}

TEST(SerialNoise, DifferenceOfWhiteNoiseIsTheMovingAverageClosedForm) {
  // A gyro read as the output at k and as the input at k - 1: r_k = eps_k -
  // eps_{k-1}, whitened by sqrt(2). Lag-1 correlation -1/2: var(sum r^2) =
  // 2 N (1 + 2 (1/2)^2) = 3 N, so 1 per sample beyond 2 (the first has none).
  const double w = 1.0 / std::sqrt(2.0);
  EXPECT_NEAR(serialSum(1000, w, w, 0.0), 999.0, 1e-9);
}

TEST(SerialNoise, LowPassedNoiseIsTheAutoregressiveClosedForm) {
  // r_k = eps_k, AR(1) with rho: var(sum r^2) -> 2 N (1 + rho^2) / (1 - rho^2),
  // i.e. 4 rho^2 / (1 - rho^2) per sample beyond 2 (up to the lags left out).
  const double rho = 0.8;
  const int n = 4000;
  const double per_sample = serialSum(n, 1.0, 0.0, rho) / n;
  EXPECT_NEAR(per_sample, 4.0 * rho * rho / (1.0 - rho * rho), 1e-2);
}

TEST(SerialNoise, IndependentSamplesAddNothing) {
  EXPECT_EQ(serialSum(100, 1.0, 0.0, 0.0), 0.0);
}

TEST(SerialNoise, TwoChannelsMatchSimulatedRecords) {
  // Two channels reading two inputs now and before (mixed loadings, one
  // input low-passed): the spread of the simulated sum of squares, once
  // whitened per sample, against 2 N + the serial sum.
  const int n = 400, runs = 4000;
  Eigen::MatrixXd now(2, 2), before(2, 2);
  now << 0.8, 0.3, -0.2, 0.9;
  before << 0.4, -0.5, 0.1, 0.6;
  Eigen::VectorXd rho(2);
  rho << 0.7, 0.0;
  // Each sample's covariance: N N' + B B' + rho (N B' + B N') per input.
  Eigen::MatrixXd cov = now * now.transpose() + before * before.transpose();
  for (int i = 0; i < 2; ++i) {
    cov += rho[i] * (now.col(i) * before.col(i).transpose() + before.col(i) * now.col(i).transpose());
  }
  const Eigen::MatrixXd l = cov.llt().matrixL();
  const Eigen::MatrixXd g = l.triangularView<Eigen::Lower>().solve(now);
  const Eigen::MatrixXd h = l.triangularView<Eigen::Lower>().solve(before);
  SerialNoise s;
  double serial = 0.0;
  for (int k = 0; k < n; ++k) serial += s.add(g, -h, rho);  // r = N eps_k + B eps_{k-1}
  std::mt19937_64 rng(7);
  std::normal_distribution<double> z;
  double sum = 0.0, square = 0.0;
  for (int run = 0; run < runs; ++run) {
    Eigen::Vector2d previous(z(rng), z(rng));  // the noise before the first sample
    double t = 0.0;
    for (int k = 0; k < n; ++k) {
      Eigen::Vector2d current;
      for (int i = 0; i < 2; ++i) {
        current[i] = rho[i] * previous[i] + std::sqrt(1.0 - rho[i] * rho[i]) * z(rng);
      }
      t += (g * current + h * previous).squaredNorm();
      previous = current;
    }
    sum += t;
    square += t * t;
  }
  const double mean = sum / runs, variance = square / runs - mean * mean;
  EXPECT_NEAR(mean, 2.0 * n, 0.02 * 2.0 * n);
  const double expected = 2.0 * 2.0 * n + serial;
  // The sample variance of 4000 runs: within about 3 x sqrt(2 / runs) of it.
  EXPECT_NEAR(variance / expected, 1.0, 0.07);
  EXPECT_GT(serial, 0.2 * 2.0 * 2.0 * n);  // the case is one that matters
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
