// The batch methods' local covariance (src/filter/local_covariance.h) on the
// linear system of test_mcmc_reference's scale ridge: y' = A y + B theta with
// B's first two columns nearly equal (only theta0 + theta1 is read), Gaussian
// germs. RK4 is affine in theta, so the whitened residuals are r0 + G xi
// exactly and the posterior is N(-P G^T r0, P), P = (I + G^T G)^-1 in germ
// units: the local covariance at any mean must be P, and ES-MDA's passes on
// this linear model give the same.
#include <gtest/gtest.h>

#include <random>

#include "linear_forced_model.h"
#include "pc_ekf/filter/batch_update.h"
#include "pc_ekf/filter/local_covariance.h"
#include "pc_ekf/filter/posterior_residual.h"
#include "pc_ekf/filter/trajectory_simulation.h"
#include "pc_ekf/pc/pc_statistics.h"

namespace pc_ekf {
namespace {

struct Ridge {
  std::shared_ptr<testing::LinearForcedModel> model;
  std::unique_ptr<ParameterMapping> mapping;
  MeasurementSeries series;
  NoiseModel noise{0.0, 1e-4};  // R = 0.01^2 for every reading
  IntegratorSettings integration{0.01};
  Eigen::Matrix3d p;            // the posterior covariance in germ units
  Eigen::Vector3d mean;         // and mean
  Eigen::Vector3d germ_scale;   // parameter units per germ unit
};

Ridge makeRidge() {
  Ridge r;
  Eigen::MatrixXd a(2, 2), b(2, 3), c = Eigen::MatrixXd::Identity(2, 2);
  a << 0.0, 1.0, -4.0, -0.4;
  b << 0.0, 0.002, 0.3, 1.0, 1.0, -0.5;
  r.model = std::make_shared<testing::LinearForcedModel>(a, b, c, Eigen::Vector3d(1.0, 1.0, 2.0));
  const GermSpec gaussian{GermFamily::kGaussian, 0.0, 0.0};
  r.mapping = std::make_unique<ParameterMapping>(
      *r.model, std::vector<UncertainParameter>{{"theta0", 1.0, 0.5, gaussian},
                                                {"theta1", 1.0, 0.5, gaussian},
                                                {"theta2", 2.0, 0.2, gaussian}});
  std::vector<double> times;
  for (int k = 1; k <= 30; ++k) times.push_back(0.1 * k);
  const auto z = simulateChannels(
      *r.model, r.mapping->fullParameters(r.mapping->valuesAtGerms(Eigen::RowVector3d(0.4, -0.2, 0.3))),
      times, r.integration);
  std::mt19937_64 rng(17);
  std::normal_distribution<double> normal;
  for (std::size_t k = 0; k < times.size(); ++k) {
    r.series.push_back({times[k], {0, 1}, z[k].col(0).head(2)});
    for (int j = 0; j < 2; ++j) r.series[k].values[j] += 0.01 * normal(rng);
  }
  const ModelPosteriorResidual residual(*r.model, *r.mapping, r.series, r.noise, r.integration, 1);
  Eigen::MatrixXd units(3, 4);
  units << 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1;
  const Eigen::MatrixXd rs = residual.residuals(units);
  const Eigen::MatrixXd g = rs.rightCols(3).colwise() - rs.col(0);
  r.p = (Eigen::Matrix3d::Identity() + g.transpose() * g).inverse();
  r.mean = -r.p * g.transpose() * rs.col(0);
  for (int i = 0; i < 3; ++i) {
    r.germ_scale[i] = r.mapping->valuesAtGerms(Eigen::RowVector3d::Unit(i))(i, 0) -
                      r.mapping->valuesAtGerms(Eigen::RowVector3d::Zero())(i, 0);
  }
  return r;
}

// Covariance of the coefficients in germ units.
Eigen::Matrix3d germCovariance(const Eigen::MatrixXd& coefficients, const Eigen::Vector3d& scale) {
  const Eigen::MatrixXd a = scale.cwiseInverse().asDiagonal() * coefficients.rightCols(coefficients.cols() - 1);
  return a * a.transpose();
}

PcPropagator makePropagator(const Ridge& r) {
  const PolynomialBasis basis(r.mapping->germs(), 1);
  const CollocationDesign design(basis, PointSequence::kGauss, 2);
  return PcPropagator(r.model, basis, design, *r.mapping, r.integration);
}

TEST(LocalCovariance, LinearModelGivesTheClosedForm) {
  const Ridge r = makeRidge();
  const PcPropagator propagator = makePropagator(r);
  // Any mean, any covariance before: the prior's coefficients moved off centre.
  Eigen::MatrixXd c = r.mapping->priorCoefficients(propagator.basis());
  c.col(0) += Eigen::Vector3d(0.1, -0.05, 0.02);
  const Eigen::Vector3d before = c.col(0);
  long runs = 0;
  ASSERT_TRUE(localCovariance(propagator, r.series, r.noise, c, &runs));
  EXPECT_EQ(runs, 7);  // 2 n + 1
  EXPECT_LT((c.col(0) - before).cwiseAbs().maxCoeff(), 1e-14);  // the mean stays
  const Eigen::Matrix3d got = germCovariance(c, r.germ_scale);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      EXPECT_NEAR(got(i, j), r.p(i, j), 1e-6 * std::sqrt(r.p(i, i) * r.p(j, j))) << i << "," << j;
    }
  }
  // The ridge is there: theta0 - theta1 wide, the sum narrow.
  const Eigen::Vector3d along(1.0, -1.0, 0.0), sum(1.0, 1.0, 0.0);
  EXPECT_GT(std::sqrt(along.dot(got * along) / sum.dot(got * sum)), 50.0);
}

TEST(LocalCovariance, EsMdaOnALinearModelIsUnchangedByIt) {
  const Ridge r = makeRidge();
  const PcPropagator propagator = makePropagator(r);
  BatchRestarts passes;
  passes.restarts = 2;
  passes.width = 1.5;
  BatchRestarts local = passes;
  local.local_covariance = true;
  const std::vector<double> alphas{4.0, 4.0, 4.0, 4.0};
  const BatchResult a = batchUpdateRestarted(propagator, r.series, r.noise, UpdateRule::kSquareRoot,
                                             alphas, SupportRule::kIgnore, passes);
  const BatchResult b = batchUpdateRestarted(propagator, r.series, r.noise, UpdateRule::kSquareRoot,
                                             alphas, SupportRule::kIgnore, local);
  EXPECT_FALSE(a.local_covariance);
  EXPECT_TRUE(b.local_covariance);
  const Eigen::Matrix3d pa = germCovariance(a.coefficients, r.germ_scale);
  const Eigen::Matrix3d pb = germCovariance(b.coefficients, r.germ_scale);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(b.mean[i], a.mean[i], 1e-12);
    EXPECT_NEAR(std::sqrt(pb(i, i)), std::sqrt(r.p(i, i)), 1e-6 * std::sqrt(r.p(i, i)));
    EXPECT_NEAR(std::sqrt(pa(i, i)), std::sqrt(r.p(i, i)), 1e-3 * std::sqrt(r.p(i, i)));
  }
}

// The mode of a Gaussian posterior is its mean: one Gauss-Newton step from
// anywhere (the residuals are affine), then no step improves.
TEST(LocalCovariance, PosteriorModeOfTheLinearModelIsTheClosedFormMean) {
  const Ridge r = makeRidge();
  const PcPropagator propagator = makePropagator(r);
  const Eigen::Vector3d start = r.mapping->valuesAtGerms(Eigen::RowVector3d(-1.0, 1.5, 0.7)).col(0);
  long runs = 0;
  const Eigen::VectorXd mode = posteriorMode(propagator, r.series, r.noise, start, 5, &runs);
  const Eigen::Vector3d expected = r.mapping->valuesAtGerms(r.mean.transpose()).col(0);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(mode[i], expected[i], 1e-6 * std::abs(r.germ_scale[i])) << i;
  }
  EXPECT_GE(runs, 2 * 7 + 1);  // two Jacobians and at least one trial
  EXPECT_LE(runs, 5 * 7 + 5 * 6);
}

TEST(LocalCovariance, RefusesAMeanAtTheSupportsEnd) {
  const Ridge r = makeRidge();
  const GermSpec beta{GermFamily::kBeta, 2.0, 2.0};
  const ParameterMapping bounded(*r.model, {{"theta0", 1.0, 0.5, beta},
                                            {"theta1", 1.0, 0.5, beta},
                                            {"theta2", 2.0, 0.2, beta}});
  const PolynomialBasis basis(bounded.germs(), 1);
  const CollocationDesign design(basis, PointSequence::kGauss, 2);
  const PcPropagator propagator(r.model, basis, design, bounded, r.integration);
  Eigen::MatrixXd coefficients = bounded.priorCoefficients(basis);
  coefficients(0, 0) = bounded.upperBound(0);  // theta0 + h is outside
  const Eigen::MatrixXd before = coefficients;
  EXPECT_FALSE(localCovariance(propagator, r.series, r.noise, coefficients));
  EXPECT_EQ(coefficients, before);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
