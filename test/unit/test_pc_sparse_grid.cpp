// Smolyak sparse grids from the germs' Gauss rules, and the leave-one-out
// error of the least-squares projection.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

#include "pc_ekf/pc/collocation_design.h"
#include "pc_ekf/pc/point_sets.h"
#include "pc_ekf/pc/sparse_grid.h"

namespace pc_ekf {
namespace {

const GermSpec kBeta22{GermFamily::kBeta, 2.0, 2.0};
const GermSpec kBeta25{GermFamily::kBeta, 2.0, 5.0};
const GermSpec kUniform{GermFamily::kUniform, 1.0, 1.0};
const GermSpec kGaussian{GermFamily::kGaussian, 1.0, 1.0};
const GermSpec kGamma3{GermFamily::kGamma, 3.0, 1.0};

std::vector<OrthonormalFamily> families(const std::vector<GermSpec>& germs) {
  std::vector<OrthonormalFamily> f;
  for (const auto& g : germs) f.emplace_back(g);
  return f;
}

// E[psi_alpha] = delta_(alpha, 0) for the orthonormal products: the rule's
// error on every basis term of total degree <= degree.
double worstIntegrationError(const std::vector<GermSpec>& germs, const SparseGridRule& rule,
                             int degree) {
  const PolynomialBasis basis(germs, degree);
  const Eigen::RowVectorXd integrals = rule.weights.transpose() * basis.evaluate(rule.nodes);
  Eigen::RowVectorXd exact = Eigen::RowVectorXd::Zero(basis.size());
  exact(0) = 1.0;
  return (integrals - exact).cwiseAbs().maxCoeff();
}

TEST(SmolyakRule, IntegratesItsDesignedDegreeExactly) {
  const std::vector<std::vector<GermSpec>> cases = {
      {kBeta22},
      {kBeta22, kBeta22},
      {kBeta22, kBeta22, kBeta22, kBeta22},
      {kUniform, kBeta25, kGaussian},
      {kGamma3, kBeta22},
      {kBeta22, kBeta22, kBeta22, kBeta22, kBeta22, kBeta22, kBeta22, kBeta22}};
  for (const auto& germs : cases) {
    const int max_level = germs.size() > 4 ? 2 : 4;
    for (int level = 0; level <= max_level; ++level) {
      const SparseGridRule rule = smolyakRule(families(germs), level);
      const int degree = smolyakExactDegree(level);
      EXPECT_NEAR(rule.weights.sum(), 1.0, 1e-13);
      EXPECT_LT(worstIntegrationError(germs, rule, degree), 1e-12)
          << germs.size() << " germs, level " << level << ", degree " << degree;
      // Not exact beyond: psi_(2L+2) of the first germ alone is integrated by
      // its (L+1)-point Gauss rule, exact only to degree 2L+1.
      EXPECT_GT(worstIntegrationError(germs, rule, degree + 1), 1e-6)
          << germs.size() << " germs, level " << level;
    }
  }
}

TEST(SmolyakRule, LevelOneInTwoDimensionsIsTheFivePointRule) {
  // (U2 x U1) + (U1 x U2) - (U1 x U1): the 2-point nodes on each axis with
  // weight 1/2 each and the centre with weight -1.
  const SparseGridRule rule = smolyakRule(families({kBeta22, kBeta22}), 1);
  ASSERT_EQ(rule.nodes.rows(), 5);
  const double a = 1.0 / std::sqrt(5.0);  // Gauss-Jacobi(1,1) 2-point nodes: +-1/sqrt(5)
  int centre = 0, axis = 0;
  for (Eigen::Index q = 0; q < 5; ++q) {
    if (rule.nodes.row(q).norm() == 0.0) {
      ++centre;
      EXPECT_NEAR(rule.weights(q), -1.0, 1e-14);
    } else {
      ++axis;
      EXPECT_NEAR(rule.nodes.row(q).cwiseAbs().maxCoeff(), a, 1e-14);
      EXPECT_NEAR(rule.weights(q), 0.5, 1e-14);
    }
  }
  EXPECT_EQ(centre, 1);
  EXPECT_EQ(axis, 4);
}

TEST(SmolyakRule, FarFewerPointsThanTheTensorRuleOfTheSameDegree) {
  // Degree 5 in 8 germs: tensor Gauss needs 3^8 = 6561 nodes.
  const SparseGridRule rule = smolyakRule(families(std::vector<GermSpec>(8, kBeta22)), 2);
  // Centre, +-b (3-point rule) and +-a (2-point rule) on each axis, and the
  // four (+-a, +-a) corners in each of the 28 pairs of axes.
  EXPECT_EQ(rule.nodes.rows(), 1 + 16 + 16 + 28 * 4);
}

TEST(SmolyakRule, RefusesBadInput) {
  EXPECT_THROW(smolyakRule({}, 2), std::invalid_argument);
  EXPECT_THROW(smolyakRule(families({kBeta22}), -1), std::invalid_argument);
}

// Nested rules: each level's nodes are among the next level's (bit for bit),
// the 1-D rule of level l is exact to degree 2l + 1 on the germ's own measure,
// and the sparse grid keeps its exactness 2L + 1.
TEST(NestedSmolyakRule, NestedExactAndSmallerForSymmetricBoundedGerms) {
  for (const GermSpec& g : {kUniform, kBeta22}) {
    const OrthonormalFamily f(g);
    ASSERT_TRUE(hasNestedRule(f));
    for (int l = 0; l <= 5; ++l) {
      const QuadratureRule r = nestedRule(f, l), next = nestedRule(f, l + 1);
      for (Eigen::Index k = 0; k < r.nodes.size(); ++k) {
        EXPECT_TRUE((next.nodes.array() == r.nodes(k)).any()) << "level " << l << " node " << k;
      }
      const int exact = 2 * l + 1;
      for (int degree = 0; degree <= exact + 1; ++degree) {
        const double integral = r.weights.dot(
            r.nodes.unaryExpr([&](double x) { return f.evaluate(x, degree)(degree); }));
        const double err = std::abs(integral - (degree == 0 ? 1.0 : 0.0));
        if (degree <= exact) {
          EXPECT_LT(err, 1e-12) << "level " << l << " degree " << degree;
        }
      }
    }
  }
  for (int n : {2, 3, 4}) {
    for (int level = 1; level <= 4; ++level) {
      const std::vector<GermSpec> germs(n, kBeta22);
      const SparseGridRule nested = smolyakRule(families(germs), level, true);
      const SparseGridRule gauss = smolyakRule(families(germs), level, false);
      EXPECT_LT(worstIntegrationError(germs, nested, smolyakExactDegree(level)), 1e-12)
          << "n " << n << " level " << level;
      EXPECT_NEAR(nested.weights.sum(), 1.0, 1e-12);
      // Shared nodes: never more points; fewer once consecutive levels share a
      // rule (measured: n = 2, 3, 4 at level 4: 49, 153, 369 against 53, 165, 385).
      EXPECT_LE(nested.nodes.rows(), gauss.nodes.rows()) << "n " << n << " level " << level;
      if (level == 4) {
        EXPECT_LT(nested.nodes.rows(), gauss.nodes.rows()) << "n " << n;
      }
    }
  }
  // Mixed: an asymmetric Beta and a Gaussian keep their Gauss rules; exactness holds.
  const std::vector<GermSpec> mixed{kUniform, kBeta25, kGaussian};
  EXPECT_LT(worstIntegrationError(mixed, smolyakRule(families(mixed), 3, true), 7), 1e-10);
  EXPECT_FALSE(hasNestedRule(OrthonormalFamily(kBeta25)));
  EXPECT_THROW(nestedRule(OrthonormalFamily(kGaussian), 2), std::invalid_argument);
}

TEST(SmolyakDesign, QuadratureAndRegressionRecoverPolynomialsOfTheOrder) {
  const PolynomialBasis basis({kBeta22, kBeta22, kBeta22, kBeta22}, 3);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> coef;
  Eigen::VectorXd c(basis.size());
  for (Eigen::Index j = 0; j < c.size(); ++j) c(j) = coef(rng);
  for (ProjectionMethod m : {ProjectionMethod::kQuadrature, ProjectionMethod::kRegression}) {
    const CollocationDesign design(basis, PointSequence::kSmolyak, 3, 1, 1e8, m);
    EXPECT_EQ(design.projection(), m);
    const Eigen::VectorXd values = design.designMatrix() * c;
    EXPECT_LT((design.project(values) - c).cwiseAbs().maxCoeff(), 1e-10) << toString(m);
  }
  // auto = least squares for a sparse grid, the quadrature for tensor Gauss.
  EXPECT_EQ(CollocationDesign(basis, PointSequence::kSmolyak, 3).projection(),
            ProjectionMethod::kRegression);
  EXPECT_EQ(CollocationDesign(basis, PointSequence::kGauss, 4).projection(),
            ProjectionMethod::kQuadrature);
}

TEST(SmolyakDesign, RefusesALevelTooLowForTheQuadratureProjection) {
  const PolynomialBasis basis({kBeta22, kBeta22}, 4);
  try {
    CollocationDesign(basis, PointSequence::kSmolyak, 3, 1, 1e8, ProjectionMethod::kQuadrature);
    FAIL() << "level 3 < order 4 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("level 3"), std::string::npos) << e.what();
  }
  // Regression on the same nodes only needs Q >= S (29 >= 15, not 13).
  EXPECT_NO_THROW(CollocationDesign(basis, PointSequence::kSmolyak, 3));
  EXPECT_THROW(CollocationDesign(basis, PointSequence::kSmolyak, 2), std::invalid_argument);
  EXPECT_THROW(
      CollocationDesign(basis, PointSequence::kHalton, 30, 1, 1e8, ProjectionMethod::kQuadrature),
      std::invalid_argument);
}

// Leave-one-out by brute force: refit without point q, predict at q.
Eigen::VectorXd bruteForceLoo(const CollocationDesign& d, const Eigen::MatrixXd& values) {
  const Eigen::Index q_count = d.pointCount(), s = d.termCount();
  Eigen::MatrixXd e(values.rows(), q_count);
  for (Eigen::Index q = 0; q < q_count; ++q) {
    Eigen::MatrixXd a(q_count - 1, s), v(q_count - 1, values.rows());
    for (Eigen::Index r = 0, k = 0; r < q_count; ++r) {
      if (r == q) continue;
      a.row(k) = d.designMatrix().row(r);
      v.row(k++) = values.col(r).transpose();
    }
    const Eigen::MatrixXd coeffs = a.colPivHouseholderQr().solve(v);  // S x m
    e.col(q) = values.col(q) - (d.designMatrix().row(q) * coeffs).transpose();
  }
  Eigen::VectorXd out(values.rows());
  for (Eigen::Index i = 0; i < values.rows(); ++i) {
    const double spread = (values.row(i).array() - values.row(i).mean()).square().sum();
    out(i) = std::sqrt(e.row(i).squaredNorm() / spread);
  }
  return out;
}

TEST(LeaveOneOut, ClosedFormEqualsBruteForce) {
  const PolynomialBasis basis({kBeta22, kBeta22}, 4);
  const std::vector<CollocationDesign> designs = {
      CollocationDesign(basis, PointSequence::kHalton, 30),
      CollocationDesign(basis, PointSequence::kHammersley, 40),
      CollocationDesign(basis, PointSequence::kGauss, 5),
      CollocationDesign(basis, PointSequence::kSmolyak, 5)};
  for (const auto& d : designs) {
    ASSERT_TRUE(d.hasLeaveOneOut());
    const Eigen::MatrixXd& xi = d.points();
    // Three responses that the order-4 basis misses to different extents.
    Eigen::MatrixXd values(3, d.pointCount());
    values.row(0) = (1.3 * xi.col(0) - 0.4 * xi.col(1)).array().exp().transpose();
    values.row(1) = (3.0 * xi.col(0).array() * xi.col(1).array()).sin().transpose();
    values.row(2) = (1.0 / (1.5 + xi.col(0).array() + 0.3 * xi.col(1).array())).transpose();
    const Eigen::VectorXd closed = d.leaveOneOutError(values);
    const Eigen::VectorXd brute = bruteForceLoo(d, values);
    ASSERT_EQ(closed.size(), 3);
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(closed(i), brute(i), 1e-10) << toString(d.sequence()) << " response " << i;
      EXPECT_GT(closed(i), 1e-8);  // none of them is a polynomial of degree 4
    }
  }
}

TEST(LeaveOneOut, ZeroForPolynomialsOfTheOrderAndUnavailableWithoutRedundancy) {
  const PolynomialBasis basis({kBeta22, kBeta22}, 2);
  const CollocationDesign d(basis, PointSequence::kHalton, 12);
  const Eigen::MatrixXd xi = d.points();
  Eigen::MatrixXd values(2, d.pointCount());
  values.row(0) = (xi.col(0).array().square() - 2.0 * xi.col(1).array() + 0.5).transpose();
  values.row(1).setConstant(0.25);  // equal at every point: nothing to leave out
  const Eigen::VectorXd loo = d.leaveOneOutError(values);
  EXPECT_LT(loo(0), 1e-12);
  EXPECT_EQ(loo(1), 0.0);
  // Q = S: every point is interpolated (h_qq = 1), no leave-one-out error.
  const CollocationDesign interpolating(basis, PointSequence::kHalton, 6);
  EXPECT_FALSE(interpolating.hasLeaveOneOut());
  EXPECT_EQ(interpolating.leaveOneOutError(Eigen::MatrixXd::Ones(1, 6)).size(), 0);
  EXPECT_THROW(d.leaveOneOutError(Eigen::MatrixXd::Ones(1, 5)), std::invalid_argument);
}

TEST(SmolyakDesign, Names) {
  EXPECT_EQ(pointSequenceFromString("smolyak"), PointSequence::kSmolyak);
  EXPECT_EQ(toString(PointSequence::kSmolyak), "smolyak");
  EXPECT_EQ(projectionMethodFromString("regression"), ProjectionMethod::kRegression);
  EXPECT_THROW(projectionMethodFromString("lsq"), std::invalid_argument);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
