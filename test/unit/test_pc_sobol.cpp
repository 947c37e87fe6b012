// Sobol indices from a PC expansion (src/pc/sobol_indices.h) against closed forms.
#include <gtest/gtest.h>

#include <cmath>

#include "pc_ekf/pc/sobol_indices.h"

namespace pc_ekf {
namespace {

// f = psi_(1,0) + 2 psi_(0,1) + psi_(1,1): variance 6, S = (1, 4)/6, T = (2, 5)/6.
TEST(SobolIndices, HandBuiltExpansion) {
  const PolynomialBasis basis({GermSpec{}, GermSpec{GermFamily::kUniform}}, 2);
  Eigen::VectorXd c = Eigen::VectorXd::Zero(basis.size());
  c[0] = 3.0;  // the mean does not count
  for (int a = 0; a < basis.size(); ++a) {
    const auto& m = basis.multiIndices()[a];
    if (m[0] == 1 && m[1] == 0) c[a] = 1.0;
    if (m[0] == 0 && m[1] == 1) c[a] = 2.0;
    if (m[0] == 1 && m[1] == 1) c[a] = 1.0;
  }
  const SobolIndices s = sobolIndices(basis, c);
  EXPECT_NEAR(s.variance, 6.0, 1e-15);
  EXPECT_NEAR(s.first[0], 1.0 / 6.0, 1e-15);
  EXPECT_NEAR(s.first[1], 4.0 / 6.0, 1e-15);
  EXPECT_NEAR(s.total[0], 2.0 / 6.0, 1e-15);
  EXPECT_NEAR(s.total[1], 5.0 / 6.0, 1e-15);
}

// The Ishigami function (a = 7, b = 0.1, x_i uniform on [-pi, pi]) projected
// by a tensor Gauss rule at degree 14: its analytic first and total indices.
TEST(SobolIndices, IshigamiFunctionAnalyticIndices) {
  const double a = 7.0, b = 0.1, pi = M_PI;
  const GermSpec u{GermFamily::kUniform};
  const PolynomialBasis basis({u, u, u}, 14);
  Eigen::MatrixXd nodes;
  Eigen::VectorXd weights;
  basis.tensorGaussRule(16, &nodes, &weights);
  Eigen::VectorXd coefficients = Eigen::VectorXd::Zero(basis.size());
  for (Eigen::Index q = 0; q < nodes.rows(); ++q) {
    const double x1 = pi * nodes(q, 0), x2 = pi * nodes(q, 1), x3 = pi * nodes(q, 2);
    const double f = std::sin(x1) + a * std::pow(std::sin(x2), 2) + b * std::pow(x3, 4) * std::sin(x1);
    coefficients += weights[q] * f * basis.evaluate(Eigen::VectorXd(nodes.row(q).transpose()));
  }
  const SobolIndices s = sobolIndices(basis, coefficients);
  const double v1 = 0.5 * std::pow(1.0 + b * std::pow(pi, 4) / 5.0, 2), v2 = a * a / 8.0;
  const double v13 = b * b * std::pow(pi, 8) * (1.0 / 18.0 - 1.0 / 50.0);
  const double v = v1 + v2 + v13;
  EXPECT_NEAR(s.variance, v, 1e-4 * v);
  EXPECT_NEAR(s.first[0], v1 / v, 1e-4);
  EXPECT_NEAR(s.first[1], v2 / v, 1e-4);
  EXPECT_NEAR(s.first[2], 0.0, 1e-4);
  EXPECT_NEAR(s.total[0], (v1 + v13) / v, 1e-4);
  EXPECT_NEAR(s.total[1], v2 / v, 1e-4);
  EXPECT_NEAR(s.total[2], v13 / v, 1e-4);
}

TEST(SobolIndices, RefusesCoefficientsOfAnotherBasis) {
  const PolynomialBasis basis({GermSpec{}}, 3);
  Eigen::MatrixXd first, total;
  Eigen::VectorXd variance;
  EXPECT_THROW(sobolPartialVariances(basis, Eigen::MatrixXd::Zero(2, 3), &first, &total, &variance),
               std::invalid_argument);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
