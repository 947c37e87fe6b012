// Multi-index total-degree basis (docs/method.md §3.3).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "pc_ekf/pc/polynomial_basis.h"

namespace pc_ekf {
namespace {

const GermSpec kBeta22{GermFamily::kBeta, 2.0, 2.0};

TEST(MultiIndex, TwoGermsOrderFourExactTable) {
  const std::vector<std::vector<int>> expected = {{0, 0},                          // degree 0
                                                  {1, 0}, {0, 1},                  // degree 1
                                                  {2, 0}, {1, 1}, {0, 2},          // degree 2
                                                  {3, 0}, {2, 1}, {1, 2}, {0, 3},  // degree 3
                                                  {4, 0}, {3, 1}, {2, 2}, {1, 3},
                                                  {0, 4}};  // degree 4
  const auto indices = totalDegreeMultiIndices(2, 4);
  EXPECT_EQ(indices.size(), 15u);
  EXPECT_EQ(indices, expected);
}

TEST(MultiIndex, ThreeGermsOrderTwoExactTable) {
  const std::vector<std::vector<int>> expected = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1},
                                                  {2, 0, 0}, {1, 1, 0}, {1, 0, 1}, {0, 2, 0},
                                                  {0, 1, 1}, {0, 0, 2}};
  EXPECT_EQ(totalDegreeMultiIndices(3, 2), expected);
}

TEST(MultiIndex, SizesAreBinomials) {
  EXPECT_EQ(totalDegreeMultiIndices(1, 5).size(), 6u);
  EXPECT_EQ(totalDegreeMultiIndices(3, 2).size(), 10u);
  EXPECT_EQ(totalDegreeMultiIndices(4, 3).size(), 35u);  // C(7, 3)
  EXPECT_EQ(totalDegreeMultiIndices(2, 0).size(), 1u);
  EXPECT_THROW(totalDegreeMultiIndices(0, 2), std::invalid_argument);
  EXPECT_THROW(totalDegreeMultiIndices(2, -1), std::invalid_argument);
}

TEST(PolynomialBasis, PaperBasisHasFifteenTermsAndSqrt5Xi) {
  const PolynomialBasis basis({kBeta22, kBeta22}, 4);
  EXPECT_EQ(basis.size(), 15);
  EXPECT_EQ(basis.dimension(), 2);
  const Eigen::Vector2d xi(0.3, -0.7);
  const Eigen::VectorXd psi = basis.evaluate(xi);
  EXPECT_DOUBLE_EQ(psi(0), 1.0);
  EXPECT_NEAR(psi(1), std::sqrt(5.0) * 0.3, 1e-15);
  EXPECT_NEAR(psi(2), std::sqrt(5.0) * -0.7, 1e-15);
  EXPECT_NEAR(psi(4), 5.0 * 0.3 * -0.7, 1e-14);  // psi_(1,1) = 5 xi1 xi2
}

TEST(PolynomialBasis, TermsAreProductsOfUnivariateValues) {
  const GermSpec gauss{GermFamily::kGaussian, 0, 0};
  const GermSpec gam{GermFamily::kGamma, 2.0, 0};
  const PolynomialBasis basis({kBeta22, gauss, gam}, 3);
  const Eigen::Vector3d xi(-0.4, 1.3, 2.2);
  const Eigen::VectorXd psi = basis.evaluate(xi);
  ASSERT_EQ(psi.size(), 20);
  for (int j = 0; j < basis.size(); ++j) {
    double expected = 1.0;
    for (int d = 0; d < 3; ++d) {
      expected *= basis.family(d).evaluate(xi(d), 3)(basis.multiIndices()[j][d]);
    }
    EXPECT_DOUBLE_EQ(psi(j), expected) << j;
  }
  // The matrix overload agrees row by row (and fixed-size/expression arguments compile).
  Eigen::MatrixXd points(2, 3);
  points << -0.4, 1.3, 2.2, 0.9, -2.0, 0.1;
  const Eigen::MatrixXd a = basis.evaluate(points);
  ASSERT_EQ(a.rows(), 2);
  ASSERT_EQ(a.cols(), 20);
  EXPECT_EQ(Eigen::VectorXd(a.row(0).transpose()), psi);
  EXPECT_EQ(Eigen::VectorXd(a.row(1).transpose()), basis.evaluate(points.row(1).transpose()));
  EXPECT_THROW(basis.evaluate(Eigen::Vector2d(0.0, 0.0)), std::invalid_argument);
}

// The matrix overload forms the recurrence and the products without the
// per-point route's allocations: the same numbers bit for bit, for every
// family, order and truncation, at points inside and outside the supports.
TEST(PolynomialBasis, MatrixOfPointsEqualsThePointByPointValuesBitForBit) {
  const GermSpec gauss{GermFamily::kGaussian, 0, 0};
  const GermSpec gam{GermFamily::kGamma, 2.5, 0};
  const GermSpec beta25{GermFamily::kBeta, 2.0, 5.0};
  const GermSpec uniform{GermFamily::kUniform, 0, 0};
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> x(-2.5, 3.0);
  BasisTruncation hyperbolic;
  hyperbolic.kind = TruncationKind::kHyperbolic;
  hyperbolic.q_norm = 0.6;
  for (int order : {0, 1, 2, 4}) {
    for (const BasisTruncation& t : {BasisTruncation{}, hyperbolic}) {
      const PolynomialBasis basis({kBeta22, gauss, gam, beta25, uniform}, order, t);
      Eigen::MatrixXd points(37, 5);
      for (Eigen::Index i = 0; i < points.size(); ++i) points(i) = x(rng);
      const Eigen::MatrixXd a = basis.evaluate(points);
      ASSERT_EQ(a.rows(), 37);
      ASSERT_EQ(a.cols(), basis.size());
      for (Eigen::Index q = 0; q < points.rows(); ++q) {
        EXPECT_EQ(Eigen::VectorXd(a.row(q).transpose()), basis.evaluate(points.row(q).transpose()))
            << "order " << order << " point " << q;
      }
    }
  }
  EXPECT_EQ(PolynomialBasis({kBeta22}, 2).evaluate(Eigen::MatrixXd(0, 1)).rows(), 0);
  EXPECT_THROW(PolynomialBasis({kBeta22}, 2).evaluate(Eigen::MatrixXd(3, 2)), std::invalid_argument);
}

TEST(PolynomialBasis, MultivariateOrthonormalityByTensorGauss) {
  const GermSpec gauss{GermFamily::kGaussian, 0, 0};
  const GermSpec beta25{GermFamily::kBeta, 2.0, 5.0};
  for (const auto& germs :
       {std::vector<GermSpec>{kBeta22, kBeta22}, std::vector<GermSpec>{beta25, gauss, kBeta22}}) {
    const PolynomialBasis basis(germs, 4);
    Eigen::MatrixXd nodes;
    Eigen::VectorXd weights;
    basis.tensorGaussRule(5, &nodes, &weights);  // exact to degree 9 >= 8 per variable
    ASSERT_EQ(nodes.rows(), std::pow(5, basis.dimension()));
    EXPECT_NEAR(weights.sum(), 1.0, 1e-14);
    const Eigen::MatrixXd a = basis.evaluate(nodes);
    const Eigen::MatrixXd gram = a.transpose() * weights.asDiagonal() * a;
    EXPECT_LT((gram - Eigen::MatrixXd::Identity(basis.size(), basis.size())).cwiseAbs().maxCoeff(),
              1e-12);
  }
}

TEST(PolynomialBasis, TensorGaussRuleIntegratesProductMoments) {
  // E[xi1^2 xi2^4] = 1/5 * 3/35 for independent Beta(2,2) germs.
  const PolynomialBasis basis({kBeta22, kBeta22}, 2);
  Eigen::MatrixXd nodes;
  Eigen::VectorXd weights;
  basis.tensorGaussRule(3, &nodes, &weights);
  const double m =
      (weights.array() * nodes.col(0).array().square() * nodes.col(1).array().pow(4)).sum();
  EXPECT_NEAR(m, 0.2 * 3.0 / 35.0, 1e-15);
}

TEST(PolynomialBasis, RejectsInvalidConfigurations) {
  EXPECT_THROW(PolynomialBasis({}, 2), std::invalid_argument);
  EXPECT_THROW(PolynomialBasis({kBeta22}, -1), std::invalid_argument);
  EXPECT_THROW(PolynomialBasis({GermSpec{GermFamily::kBeta, -1.0, 2.0}}, 2), std::invalid_argument);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
