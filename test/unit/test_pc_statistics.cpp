// Moments and sampled PDFs of PC expansions (docs/method.md §3.6).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <stdexcept>

#include "pc_ekf/pc/pc_statistics.h"

namespace pc_ekf {
namespace {

const GermSpec kBeta22{GermFamily::kBeta, 2.0, 2.0};

PolynomialBasis paperBasis() { return PolynomialBasis({kBeta22, kBeta22}, 4); }

// M(xi) = 200 + 100 xi1 in the paper basis (docs/method.md §3.6).
Eigen::VectorXd massCoefficients() {
  Eigen::VectorXd c = Eigen::VectorXd::Zero(15);
  c(0) = 200.0;
  c(1) = 100.0 / std::sqrt(5.0);
  return c;
}

// The germ draws' generator is std::mt19937_64's stream, and its discard
// skips as that many calls do (the PDF set-up's threads start with it).
TEST(GermGenerator, EqualsTheStandardEngineAndItsDiscard) {
  for (std::uint64_t seed : {0ULL, 11ULL, 5489ULL, 0xFFFFFFFFFFFFFFFFULL}) {
    std::mt19937_64 standard(seed);
    GermGenerator fast(seed);
    for (int i = 0; i < 200000; ++i) ASSERT_EQ(fast(), standard()) << "seed " << seed << " output " << i;
  }
  for (unsigned long long skip : {0ULL, 1ULL, 311ULL, 312ULL, 313ULL, 624ULL, 100007ULL}) {
    std::mt19937_64 standard(11);
    GermGenerator fast(11);
    standard();  // from inside a block as well
    fast();
    standard.discard(skip);
    fast.discard(skip);
    for (int i = 0; i < 1000; ++i) ASSERT_EQ(fast(), standard()) << "after discard " << skip;
  }
}

TEST(PcStatistics, MeanCovarianceStddevFromCoefficients) {
  Eigen::MatrixXd c(2, 3);
  c << 1, 2, 3,  //
      4, 5, -6;
  EXPECT_EQ(pcMean(c), Eigen::Vector2d(1, 4));
  Eigen::Matrix2d cov;
  cov << 13, -8,  //
      -8, 61;     // 2*5 + 3*(-6) = -8
  EXPECT_EQ(pcCovariance(c), Eigen::MatrixXd(cov));
  EXPECT_NEAR(pcStddev(c)(0), std::sqrt(13.0), 1e-15);
  EXPECT_NEAR(pcStddev(c)(1), std::sqrt(61.0), 1e-15);
  // A single (mean-only) term has zero spread.
  EXPECT_EQ(pcStddev(Eigen::MatrixXd::Constant(3, 1, 7.0)), Eigen::VectorXd::Zero(3));
  EXPECT_THROW(pcMean(Eigen::MatrixXd(2, 0)), std::invalid_argument);
}

TEST(PcStatistics, SampledGermsFollowTheirDistributions) {
  const GermSpec gauss{GermFamily::kGaussian, 0, 0};
  const GermSpec gam{GermFamily::kGamma, 3.0, 0};
  const PolynomialBasis basis({kBeta22, gauss, gam}, 1);
  const Eigen::MatrixXd xi = sampleGerms(basis, 100000, 42);
  ASSERT_EQ(xi.rows(), 100000);
  ASSERT_EQ(xi.cols(), 3);
  EXPECT_TRUE((xi.col(0).array() > -1.0).all() && (xi.col(0).array() < 1.0).all());
  EXPECT_TRUE((xi.col(2).array() > 0.0).all());
  const Eigen::RowVectorXd mean = xi.colwise().mean();
  const Eigen::RowVectorXd var =
      (xi.rowwise() - mean).array().square().colwise().sum() / (xi.rows() - 1.0);
  // Tolerances are ~5 standard errors of 1e5 draws.
  EXPECT_NEAR(mean(0), 0.0, 0.0075);
  EXPECT_NEAR(var(0), 0.2, 0.003);  // E[xi^2] = 1/5
  EXPECT_NEAR(mean(1), 0.0, 0.016);
  EXPECT_NEAR(var(1), 1.0, 0.025);
  EXPECT_NEAR(mean(2), 3.0, 0.03);
  EXPECT_NEAR(var(2), 3.0, 0.15);
}

TEST(PcHistogram, UnitAreaMeanAndShapeOfTheMassPdf) {
  const PolynomialBasis basis = paperBasis();
  double outside = -1.0;
  const Histogram h = pcHistogram(basis, massCoefficients(), 100000, 50, 7, 0.0, 0.0, &outside);
  ASSERT_EQ(h.edges.size(), 51);
  ASSERT_EQ(h.densities.size(), 50);
  const double width = h.edges(1) - h.edges(0);
  EXPECT_NEAR(h.densities.sum() * width, 1.0, 1e-12);
  EXPECT_EQ(outside, 0.0);
  // Sample range lies within the support [100, 300] of M.
  EXPECT_GE(h.edges(0), 100.0);
  EXPECT_LE(h.edges(50), 300.0);
  EXPECT_LT(h.edges(0), 105.0);
  EXPECT_GT(h.edges(50), 295.0);
  // Histogram mean and std against the PC values 200 and 100/sqrt(5) = 44.72.
  const Eigen::VectorXd centres = h.centres();
  const double mean = (centres.array() * h.densities.array()).sum() * width;
  const double var = ((centres.array() - mean).square() * h.densities.array()).sum() * width;
  EXPECT_NEAR(mean, 200.0, 0.6);
  EXPECT_NEAR(std::sqrt(var), 100.0 / std::sqrt(5.0), 0.5);
  // Shape: the exact PDF of M is 3/4 (1 - t^2) / 100, t = (m - 200)/100; peak 0.0075.
  for (int b = 10; b < 40; ++b) {
    const double t = (centres(b) - 200.0) / 100.0;
    EXPECT_NEAR(h.densities(b), 0.0075 * (1.0 - t * t), 6e-4) << "bin " << b;
  }
}

TEST(PcHistogram, FixedRangeReportsTheMassOutside) {
  double outside = -1.0;
  const Histogram h =
      pcHistogram(paperBasis(), massCoefficients(), 100000, 20, 3, 200.0, 300.0, &outside);
  EXPECT_DOUBLE_EQ(h.edges(0), 200.0);
  EXPECT_DOUBLE_EQ(h.edges(20), 300.0);
  // Area equals the in-range fraction: together with the outside mass, exactly 1.
  const double area = h.densities.sum() * 5.0;
  EXPECT_NEAR(area + outside, 1.0, 1e-12);
  EXPECT_NEAR(outside, 0.5, 0.008);  // M is symmetric about 200
}

TEST(PcHistogram, SeededAndReproducible) {
  const Histogram a = pcHistogram(paperBasis(), massCoefficients(), 20000, 30, 99);
  const Histogram b = pcHistogram(paperBasis(), massCoefficients(), 20000, 30, 99);
  const Histogram c = pcHistogram(paperBasis(), massCoefficients(), 20000, 30, 100);
  EXPECT_EQ(a.edges, b.edges);
  EXPECT_EQ(a.densities, b.densities);
  EXPECT_NE(a.densities, c.densities);
}

TEST(PcHistogram, ConstantExpansionAndInvalidInput) {
  Eigen::VectorXd c = Eigen::VectorXd::Zero(15);
  c(0) = 5.0;
  const Histogram h = pcHistogram(paperBasis(), c, 1000, 4, 1);
  EXPECT_NEAR(h.densities.sum() * (h.edges(1) - h.edges(0)), 1.0, 1e-12);
  EXPECT_LE(h.edges(0), 5.0);
  EXPECT_GE(h.edges(4), 5.0);
  EXPECT_THROW(pcHistogram(paperBasis(), Eigen::VectorXd::Zero(3), 100, 4, 1),
               std::invalid_argument);
  EXPECT_THROW(pcHistogram(paperBasis(), c, 0, 4, 1), std::invalid_argument);
  EXPECT_THROW(pcHistogram(paperBasis(), c, 100, 0, 1), std::invalid_argument);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
