// Hyperbolic-cross (q-norm) truncation of the PC basis: the kept set against
// brute-force enumeration, q = 1 as total degree, orthonormality and exact
// recovery of polynomials in the truncated space.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <vector>

#include "pc_ekf/pc/basis_truncation.h"
#include "pc_ekf/pc/collocation_design.h"
#include "pc_ekf/pc/polynomial_basis.h"

namespace pc_ekf {
namespace {

const GermSpec kBeta22{GermFamily::kBeta, 2.0, 2.0};
const GermSpec kUniform{GermFamily::kUniform, 0.0, 0.0};
const GermSpec kGaussian{GermFamily::kGaussian, 0.0, 0.0};

// Every alpha in {0..p}^n with (sum alpha_i^q)^(1/q) <= p, by the definition.
std::set<std::vector<int>> bruteForce(int n, int p, double q) {
  std::set<std::vector<int>> kept;
  std::vector<int> alpha(n, 0);
  while (true) {
    double sum = 0.0;
    for (int a : alpha) sum += std::pow(a, q);
    if (std::pow(sum, 1.0 / q) <= p + 1e-9) kept.insert(alpha);
    int d = 0;
    while (d < n && ++alpha[d] > p) alpha[d++] = 0;
    if (d == n) return kept;
  }
}

TEST(HyperbolicTruncation, KeptSetEqualsBruteForceEnumeration) {
  for (int n : {1, 2, 3, 4, 6}) {
    for (int p : {1, 2, 3, 4, 6}) {
      for (double q : {0.3, 0.5, 0.75, 1.0}) {
        const auto indices = hyperbolicMultiIndices(n, p, q);
        const std::set<std::vector<int>> as_set(indices.begin(), indices.end());
        EXPECT_EQ(as_set.size(), indices.size()) << "duplicates, n " << n << " p " << p;
        EXPECT_EQ(as_set, bruteForce(n, p, q)) << "n " << n << " p " << p << " q " << q;
        // Every univariate term up to degree p stays.
        for (int d = 0; d < n; ++d) {
          std::vector<int> pure(n, 0);
          pure[d] = p;
          EXPECT_TRUE(as_set.count(pure));
        }
      }
    }
  }
  // Hand counts: n = 2, p = 4, q = 0.5 keeps 1 + 2 * 4 + (1, 1): S = 10 of 15.
  EXPECT_EQ(hyperbolicMultiIndices(2, 4, 0.5).size(), 10u);
  // q small enough: no interaction at all, S = 1 + n p.
  EXPECT_EQ(hyperbolicMultiIndices(8, 3, 0.2).size(), 25u);
}

TEST(HyperbolicTruncation, QOneIsTotalDegreeExactly) {
  for (int n : {1, 2, 4, 8}) {
    for (int p : {0, 1, 3, 5}) {
      EXPECT_EQ(hyperbolicMultiIndices(n, p, 1.0), totalDegreeMultiIndices(n, p));
      const BasisTruncation hyperbolic{TruncationKind::kHyperbolic, 1.0};
      EXPECT_EQ(PolynomialBasis(std::vector<GermSpec>(n, kBeta22), p, hyperbolic).multiIndices(),
                PolynomialBasis(std::vector<GermSpec>(n, kBeta22), p).multiIndices());
    }
  }
}

TEST(HyperbolicTruncation, KeepsTheGradedOrder) {
  const auto indices = hyperbolicMultiIndices(3, 5, 0.6);
  const auto full = totalDegreeMultiIndices(3, 5);
  // A subsequence of the total-degree order, starting with the constant and
  // the first-order terms (the parameters' linear coefficients sit there).
  auto it = full.begin();
  for (const auto& alpha : indices) {
    it = std::find(it, full.end(), alpha);
    ASSERT_NE(it, full.end());
  }
  ASSERT_GE(indices.size(), 4u);
  EXPECT_EQ(indices[0], (std::vector<int>{0, 0, 0}));
  EXPECT_EQ(indices[1], (std::vector<int>{1, 0, 0}));
  EXPECT_EQ(indices[3], (std::vector<int>{0, 0, 1}));
}

TEST(HyperbolicTruncation, TruncatedBasisIsOrthonormalByGaussQuadrature) {
  const BasisTruncation t{TruncationKind::kHyperbolic, 0.5};
  const PolynomialBasis basis({kBeta22, kUniform, kGaussian}, 6, t);
  ASSERT_LT(basis.size(), static_cast<int>(totalDegreeMultiIndices(3, 6).size()));
  Eigen::MatrixXd nodes;
  Eigen::VectorXd weights;
  basis.tensorGaussRule(7, &nodes, &weights);  // exact to degree 13 >= 12 per variable
  const Eigen::MatrixXd a = basis.evaluate(nodes);
  const Eigen::MatrixXd gram = a.transpose() * weights.asDiagonal() * a;
  EXPECT_LT((gram - Eigen::MatrixXd::Identity(basis.size(), basis.size())).cwiseAbs().maxCoeff(),
            1e-12);
}

TEST(HyperbolicTruncation, RegressionRecoversAPolynomialOfTheTruncatedSpace) {
  const std::vector<GermSpec> germs(4, kBeta22);
  const BasisTruncation t{TruncationKind::kHyperbolic, 0.5};
  const PolynomialBasis truncated(germs, 4, t);
  const PolynomialBasis full(germs, 4);
  // A random polynomial on the kept multi-indices, evaluated through the
  // full total-degree basis (its other coefficients zero).
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  Eigen::VectorXd kept_coeffs(truncated.size()), full_coeffs = Eigen::VectorXd::Zero(full.size());
  for (int j = 0; j < truncated.size(); ++j) {
    kept_coeffs(j) = normal(rng);
    const auto& all = full.multiIndices();
    const auto pos = std::find(all.begin(), all.end(), truncated.multiIndices()[j]) - all.begin();
    full_coeffs(pos) = kept_coeffs(j);
  }
  const CollocationDesign design(truncated, PointSequence::kHalton, 2 * truncated.size());
  const Eigen::VectorXd values = full.evaluate(design.points()) * full_coeffs;
  const Eigen::VectorXd recovered = design.project(values);
  EXPECT_LT((recovered - kept_coeffs).cwiseAbs().maxCoeff(), 1e-10);
  // A term outside the set is not representable: the fit leaves a residual.
  std::vector<int> dropped{2, 2, 0, 0};  // q-norm (2 sqrt 2)^2 = 8 > 4
  const auto pos = std::find(full.multiIndices().begin(), full.multiIndices().end(), dropped) -
                   full.multiIndices().begin();
  ASSERT_LT(pos, full.size());
  const Eigen::VectorXd outside = full.evaluate(design.points()).col(pos);
  const Eigen::VectorXd fitted = design.designMatrix() * design.project(outside);
  EXPECT_GT((outside - fitted).norm(), 0.1 * outside.norm());
}

// Closed form: C(a + p, p) terms without a tolerance germ; per tolerance germ
// and degree d = 1..p, the terms of degree <= p - d in the a free germs.
std::size_t binomial(int n, int k) {
  double r = 1.0;
  for (int i = 1; i <= k; ++i) r = r * (n - k + i) / i;
  return static_cast<std::size_t>(std::llround(r));
}

TEST(SingleToleranceTerms, CountIsTheClosedFormAndEveryTermHasOneToleranceAtMost) {
  for (int free : {0, 1, 2, 3}) {
    for (int tolerances : {1, 4, 14}) {
      for (int p : {1, 2, 3}) {
        BasisTruncation t;
        t.single_from = free;
        const int n = free + tolerances;
        const auto kept = truncatedMultiIndices(n, p, t);
        std::size_t expected = binomial(free + p, p);
        for (int d = 1; d <= p; ++d) expected += tolerances * binomial(free + p - d, p - d);
        EXPECT_EQ(kept.size(), expected) << free << " free, " << tolerances << " tolerances, p " << p;
        for (const auto& alpha : kept) {
          int count = 0, degree = 0;
          for (int i = 0; i < n; ++i) {
            count += i >= free && alpha[i] != 0;
            degree += alpha[i];
          }
          EXPECT_LE(count, 1);
          EXPECT_LE(degree, p);
        }
      }
    }
  }
  // vehicle_imu.yaml's size: 2 payload germs, 14 tolerances, p = 2.
  BasisTruncation t;
  t.single_from = 2;
  EXPECT_EQ(truncatedMultiIndices(16, 2, t).size(), 62u);
  // The hyperbolic cross and the limit together: both filters apply.
  t.kind = TruncationKind::kHyperbolic;
  t.q_norm = 0.5;  // p = 2: no interaction at all survives
  EXPECT_EQ(truncatedMultiIndices(16, 2, t).size(), 1u + 16u + 16u);
}

TEST(SingleToleranceTerms, AToleranceInteractionIsNotRepresented) {
  // Germs 0 (free) and 1, 2 (tolerances): xi0 xi1 is in the basis, xi1 xi2 is not.
  BasisTruncation t;
  t.single_from = 1;
  const PolynomialBasis kept({kBeta22, kBeta22, kBeta22}, 2, t);
  const auto& idx = kept.multiIndices();
  EXPECT_NE(std::find(idx.begin(), idx.end(), std::vector<int>{1, 1, 0}), idx.end());
  EXPECT_EQ(std::find(idx.begin(), idx.end(), std::vector<int>{0, 1, 1}), idx.end());
  EXPECT_NE(std::find(idx.begin(), idx.end(), std::vector<int>{0, 0, 2}), idx.end());
  EXPECT_EQ(kept.size(), 10u - 1u);
}

TEST(HyperbolicTruncation, RejectsQNormOutsideTheUnitInterval) {
  EXPECT_THROW(hyperbolicMultiIndices(2, 3, 0.0), std::invalid_argument);
  EXPECT_THROW(hyperbolicMultiIndices(2, 3, 1.5), std::invalid_argument);
  EXPECT_THROW(PolynomialBasis({kBeta22}, 2, BasisTruncation{TruncationKind::kHyperbolic, -1.0}),
               std::invalid_argument);
  EXPECT_THROW(truncationKindFromString("q_norm"), std::invalid_argument);
  EXPECT_EQ(truncationKindFromString(toString(TruncationKind::kHyperbolic)),
            TruncationKind::kHyperbolic);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
