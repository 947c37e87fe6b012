// Collocation designs and the least-squares projection (docs/method.md §3.4, §3.5).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

#include "pc_ekf/pc/collocation_design.h"
#include "pc_ekf/pc/pc_statistics.h"
#include "pc_ekf/pc/point_sets.h"

namespace pc_ekf {
namespace {

const GermSpec kBeta22{GermFamily::kBeta, 2.0, 2.0};

PolynomialBasis paperBasis() { return PolynomialBasis({kBeta22, kBeta22}, 4); }

// A random polynomial of total degree <= 4 in monomials, independent of the basis.
struct MonomialPolynomial {
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(5, 5);  // c(a, b) of xi1^a xi2^b, a + b <= 4
  explicit MonomialPolynomial(std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> coef(-3.0, 3.0);
    for (int a = 0; a <= 4; ++a) {
      for (int b = 0; a + b <= 4; ++b) c(a, b) = coef(rng);
    }
  }
  Eigen::VectorXd operator()(const Eigen::MatrixXd& xi) const {
    Eigen::VectorXd v = Eigen::VectorXd::Zero(xi.rows());
    for (int a = 0; a <= 4; ++a) {
      for (int b = 0; a + b <= 4; ++b) {
        v += c(a, b) * (xi.col(0).array().pow(a) * xi.col(1).array().pow(b)).matrix();
      }
    }
    return v;
  }
};

TEST(CollocationDesign, PaperHaltonDesignIsWellPosed) {
  const CollocationDesign design(paperBasis(), PointSequence::kHalton, 30);
  EXPECT_EQ(design.pointCount(), 30);
  EXPECT_EQ(design.termCount(), 15);
  // The first Halton point (1/2, 1/3) mapped by the Beta(2,2) inverse CDF.
  EXPECT_NEAR(design.points()(0, 0), 0.0, 1e-15);
  EXPECT_NEAR(design.points()(0, 1), beta22InverseCdf(1 / 3.0), 1e-15);
  EXPECT_GT(design.conditionNumber(), 1.0);
  EXPECT_LT(design.conditionNumber(), 50.0);  // measured 9.5
  // Full column rank: the projector is a left inverse of A.
  const Eigen::MatrixXd pa = design.projector() * design.designMatrix();
  EXPECT_LT((pa - Eigen::MatrixXd::Identity(15, 15)).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(CollocationDesign, HaltonProjectionRecoversDegreeFourPolynomials) {
  const PolynomialBasis basis = paperBasis();
  const CollocationDesign design(basis, PointSequence::kHalton, 30);
  // Independent reference coefficients: a tensor Gauss rule exact to degree 9 per variable.
  const CollocationDesign gauss(basis, PointSequence::kGauss, 5);
  const Eigen::MatrixXd check_points = mapToGerms(haltonPoints(50, 2, 1000), basis.germs());
  for (std::uint64_t seed : {1u, 2u, 3u, 4u, 5u}) {
    const MonomialPolynomial f(seed);
    const Eigen::VectorXd coeffs = design.project(f(design.points()));
    const Eigen::VectorXd reference = gauss.project(f(gauss.points()));
    EXPECT_LT((coeffs - reference).cwiseAbs().maxCoeff(), 1e-10) << "seed " << seed;
    const Eigen::VectorXd at_check = basis.evaluate(check_points) * coeffs;
    EXPECT_LT((at_check - f(check_points)).cwiseAbs().maxCoeff(), 1e-10) << "seed " << seed;
  }
}

TEST(CollocationDesign, HammersleyProjectionRecoversDegreeFourPolynomials) {
  const PolynomialBasis basis = paperBasis();
  const CollocationDesign design(basis, PointSequence::kHammersley, 30);
  EXPECT_NEAR(design.points()(0, 0), beta22InverseCdf(0.5 / 30), 1e-15);
  const MonomialPolynomial f(11);
  const Eigen::MatrixXd check = mapToGerms(haltonPoints(40, 2, 77), basis.germs());
  const Eigen::VectorXd coeffs = design.project(f(design.points()));
  EXPECT_LT((basis.evaluate(check) * coeffs - f(check)).cwiseAbs().maxCoeff(), 1e-10);
}

TEST(CollocationDesign, ProjectionIsLeastSquaresForNonPolynomials) {
  // Residual of a non-polynomial fit is orthogonal to the columns of A.
  const CollocationDesign design(paperBasis(), PointSequence::kHalton, 30);
  const Eigen::VectorXd f =
      (design.points().col(0).array() * 3.0).exp() + design.points().col(1).array().cos();
  const Eigen::VectorXd c = design.project(f);
  const Eigen::VectorXd residual = design.designMatrix() * c - f;
  EXPECT_GT(residual.norm(), 1e-3);  // genuinely not interpolated
  EXPECT_LT((design.designMatrix().transpose() * residual).cwiseAbs().maxCoeff(), 1e-10);
}

TEST(CollocationDesign, MassExpansionOfThePaper) {
  // M(xi) = 200 + 100 xi1 -> (200, 100/sqrt(5), 0, ...); d_CG = 0.762 (1 + 0.25 xi2).
  const CollocationDesign design(paperBasis(), PointSequence::kHalton, 30);
  Eigen::MatrixXd values(30, 2);
  values.col(0) = (200.0 + 100.0 * design.points().col(0).array()).matrix();
  values.col(1) = (0.762 * (1.0 + 0.25 * design.points().col(1).array())).matrix();
  const Eigen::MatrixXd coeffs = design.project(values).transpose();  // 2 x S
  Eigen::MatrixXd expected = Eigen::MatrixXd::Zero(2, 15);
  expected(0, 0) = 200.0;
  expected(0, 1) = 100.0 / std::sqrt(5.0);
  expected(1, 0) = 0.762;
  expected(1, 2) = 0.762 * 0.25 / std::sqrt(5.0);
  EXPECT_LT((coeffs - expected).cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_NEAR(pcStddev(coeffs)(0), 100.0 / std::sqrt(5.0), 1e-10);  // 44.72 kg
  EXPECT_NEAR(pcMean(coeffs)(1), 0.762, 1e-12);
  // Round trip through evaluateAtPoints.
  EXPECT_LT((design.evaluateAtPoints(coeffs) - values.transpose()).cwiseAbs().maxCoeff(), 1e-10);
}

TEST(CollocationDesign, RefusesFewerPointsThanTerms) {
  try {
    CollocationDesign design(paperBasis(), PointSequence::kHalton, 10);
    FAIL() << "a 10-point design for 15 terms was accepted";
  } catch (const std::invalid_argument& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("degenerate"), std::string::npos) << msg;
    EXPECT_NE(msg.find("Q = 10"), std::string::npos) << msg;
    EXPECT_NE(msg.find("S = 15"), std::string::npos) << msg;
  }
  EXPECT_THROW(CollocationDesign(paperBasis(), PointSequence::kHammersley, 14),
               std::invalid_argument);
  EXPECT_NO_THROW(CollocationDesign(paperBasis(), PointSequence::kHalton, 15));
  // Gauss: 3 nodes per dimension = 9 points < 15.
  EXPECT_THROW(CollocationDesign(paperBasis(), PointSequence::kGauss, 3), std::invalid_argument);
}

TEST(CollocationDesign, RefusesIllConditionedDesigns) {
  // 4 Gauss nodes per variable: 16 >= 15 points, but psi_4 vanishes on all of them.
  try {
    CollocationDesign design(paperBasis(), PointSequence::kGauss, 4);
    FAIL() << "a rank-deficient design was accepted";
  } catch (const std::invalid_argument& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("condition number"), std::string::npos) << msg;
    EXPECT_NE(msg.find("Q = 16"), std::string::npos) << msg;
  }
  // The paper design is fine at the default limit but not under an absurd one.
  EXPECT_THROW(CollocationDesign(paperBasis(), PointSequence::kHalton, 30, 1, 1.0),
               std::invalid_argument);
}

TEST(CollocationDesign, GaussDesignIsTheWeightedDiscreteProjection) {
  const PolynomialBasis basis = paperBasis();
  const CollocationDesign design(basis, PointSequence::kGauss, 5);
  EXPECT_EQ(design.pointCount(), 25);
  // W^(1/2) A has orthonormal columns when the rule is exact to degree 2p = 8.
  EXPECT_NEAR(design.conditionNumber(), 1.0, 1e-12);
  // Exact for degree <= 2*5 - 1 - 4 = 5 per variable: a degree-5 term is recovered too.
  const Eigen::VectorXd xi1 = design.points().col(0);
  const Eigen::VectorXd f = xi1.array().pow(5);
  const Eigen::VectorXd c = design.project(f);
  // E[xi^5 * sqrt(5) xi] = sqrt(5) E[xi^6] = sqrt(5) * 5/105 for Beta(2,2).
  EXPECT_NEAR(c(1), std::sqrt(5.0) * 5.0 / 105.0, 1e-14);
  EXPECT_NEAR(c(0), 0.0, 1e-14);
}

TEST(CollocationDesign, PointSequenceNames) {
  for (PointSequence s :
       {PointSequence::kHalton, PointSequence::kHammersley, PointSequence::kGauss}) {
    EXPECT_EQ(pointSequenceFromString(toString(s)), s);
  }
  EXPECT_EQ(toString(PointSequence::kHalton), "halton");
  EXPECT_THROW(pointSequenceFromString("sobol"), std::invalid_argument);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
