// Sampling reference posterior (mcmc_reference.h): the convergence diagnostics
// on sequences with known answers, the sampler on posteriors in closed form
// (Gaussian prior x linear-Gaussian likelihood; Beta(2,2) prior alone), then
// the two-parameter speed-bump case against the grid posterior; the ensemble
// and Hamiltonian samplers on a 100:1 Gaussian ridge and on a linear model
// whose two inputs trade off (the likelihood exactly Gaussian through the
// model path).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "pc_ekf/reference/mcmc_reference.h"
#include "linear_forced_model.h"
#include "linear_residual.h"
#include "pc_ekf/reference/reference_posterior.h"
#include "pc_ekf/filter/trajectory_simulation.h"
#include "pc_ekf/model/roll_plane_model.h"

namespace pc_ekf {
namespace {

GermSpec germ(GermFamily family) {
  GermSpec g;
  g.family = family;
  g.alpha = 2.0;
  g.beta = 2.0;
  return g;
}

using testing::LinearResidual;

TEST(McmcDiagnostics, IndependentDrawsHaveFullSizeAndUnitRHat) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd c(4, 4000);
  for (Eigen::Index j = 0; j < c.cols(); ++j) {
    for (Eigen::Index i = 0; i < c.rows(); ++i) c(i, j) = normal(rng);
  }
  EXPECT_NEAR(effectiveSampleSize(c) / c.size(), 1.0, 0.1);
  EXPECT_LT(splitRHat(c), 1.01);
}

TEST(McmcDiagnostics, AutoregressiveChainHasTheClosedFormSize) {
  // AR(1) with coefficient phi: integrated autocorrelation (1 + phi) / (1 - phi).
  const double phi = 0.9;
  std::mt19937_64 rng(11);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd c(4, 40000);
  for (Eigen::Index i = 0; i < c.rows(); ++i) {
    double x = normal(rng) / std::sqrt(1.0 - phi * phi);  // stationary start
    for (Eigen::Index j = 0; j < c.cols(); ++j) {
      x = phi * x + normal(rng);
      c(i, j) = x;
    }
  }
  const double expected = c.size() * (1.0 - phi) / (1.0 + phi);
  EXPECT_NEAR(effectiveSampleSize(c) / expected, 1.0, 0.1);
  EXPECT_LT(splitRHat(c), 1.01);
}

TEST(McmcDiagnostics, ChainsAtDifferentLevelsOrADriftAreNotConverged) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd apart(4, 1000), drift(1, 1000);
  for (Eigen::Index j = 0; j < apart.cols(); ++j) {
    for (Eigen::Index i = 0; i < apart.rows(); ++i)
      apart(i, j) = normal(rng) + (i == 0 ? 2.0 : 0.0);
    drift(0, j) = normal(rng) + 4.0 * j / 1000.0;  // one chain: its halves disagree
  }
  EXPECT_GT(splitRHat(apart), 1.1);
  EXPECT_GT(splitRHat(drift), 1.1);
  EXPECT_THROW(splitRHat(Eigen::MatrixXd(2, 3)), std::invalid_argument);
}

TEST(McmcReference, GaussianPriorTimesCorrelatedLikelihoodIsClosedForm) {
  // Prior N(0, I), likelihood N(mu, S): posterior N(P S^-1 mu, P), P = (I + S^-1)^-1.
  Eigen::Matrix3d s;
  s << 0.04, 0.03, 0.0, 0.03, 0.09, -0.02, 0.0, -0.02, 0.25;
  const Eigen::Vector3d mu(0.5, -0.3, 1.0);
  const LinearResidual residual(mu, s.llt().matrixL(), true);
  const Eigen::Matrix3d p = (Eigen::Matrix3d::Identity() + s.inverse()).inverse();
  const Eigen::Vector3d mean = p * s.inverse() * mu;
  McmcSettings settings;
  settings.burn_in = 1000;
  settings.samples = 6000;
  const std::vector<GermSpec> prior(3, germ(GermFamily::kGaussian));
  const McmcReference r = runMcmcReference(residual, prior, {Eigen::Vector3d::Zero()}, settings);
  for (int i = 0; i < 3; ++i) {
    const double sd = std::sqrt(p(i, i));
    EXPECT_NEAR(r.mode_xi[i], mean[i], 1e-6) << i;  // the posterior is Gaussian: mode = mean
    EXPECT_NEAR(r.laplace_xi_stddev[i], sd, 1e-6) << i;
    EXPECT_NEAR(r.xi_mean[i], mean[i], 5.0 * r.mean_error[i]) << i;
    EXPECT_LT(r.mean_error[i], 0.03 * sd) << i;
    EXPECT_NEAR(r.xi_stddev[i], sd, 0.05 * sd) << i;
    EXPECT_LT(r.r_hat[i], 1.02) << i;
    EXPECT_GT(r.effective_size[i], 1000.0) << i;
  }
  EXPECT_NEAR(r.xi_covariance(0, 1), p(0, 1), 0.1 * std::sqrt(p(0, 0) * p(1, 1)));
  EXPECT_GT(r.acceptance, 0.15);
  EXPECT_LT(r.acceptance, 0.35);
  EXPECT_GE(r.simulations,
            static_cast<long>(settings.chains) * (settings.burn_in + settings.samples));
}

TEST(McmcReference, UninformativeDataReturnTheBetaPrior) {
  // Likelihood std 100 on a Beta(2,2) germ on [-1, 1]: the posterior is the
  // prior, mean 0 and std 1/sqrt(5); proposals outside the support are refused.
  const LinearResidual residual(Eigen::Vector2d::Zero(), 100.0 * Eigen::Matrix2d::Identity(),
                                true);
  McmcSettings settings;
  settings.burn_in = 1000;
  settings.samples = 6000;
  settings.seed = 5;
  const std::vector<GermSpec> prior(2, germ(GermFamily::kBeta));
  const McmcReference r = runMcmcReference(residual, prior, {Eigen::Vector2d(0.3, -0.2)}, settings);
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(r.xi_mean[i], 0.0, 5.0 * r.mean_error[i]) << i;
    EXPECT_NEAR(r.xi_stddev[i], 1.0 / std::sqrt(5.0), 0.03) << i;
    EXPECT_LT(r.r_hat[i], 1.02) << i;
    for (const auto& chain : r.draws) EXPECT_LE(chain.row(i).cwiseAbs().maxCoeff(), 1.0);
  }
}

TEST(McmcReference, BadInputIsRefusedWithItsName) {
  const LinearResidual residual(Eigen::Vector2d::Zero(), Eigen::Matrix2d::Identity(), true);
  const std::vector<GermSpec> prior(2, germ(GermFamily::kGaussian));
  McmcSettings s;
  EXPECT_THROW(
      runMcmcReference(residual, {germ(GermFamily::kGaussian)}, {Eigen::Vector2d::Zero()}, s),
      std::invalid_argument);
  EXPECT_THROW(runMcmcReference(residual, prior, {}, s), std::invalid_argument);
  EXPECT_THROW(runMcmcReference(residual, prior, {Eigen::Vector3d::Zero()}, s),
               std::invalid_argument);
  s.chains = 1;
  EXPECT_THROW(runMcmcReference(residual, prior, {Eigen::Vector2d::Zero()}, s),
               std::invalid_argument);
  s.sampler = McmcSampler::kEnsemble;
  s.chains = 5;  // odd
  EXPECT_THROW(runMcmcReference(residual, prior, {Eigen::Vector2d::Zero()}, s),
               std::invalid_argument);
  s.chains = 2;  // fewer than 2 n walkers
  EXPECT_THROW(runMcmcReference(residual, prior, {Eigen::Vector2d::Zero()}, s),
               std::invalid_argument);
  s.sampler = McmcSampler::kConditionalLaplace;
  s.ridge_dimensions = 3;  // more than n
  EXPECT_THROW(runMcmcReference(residual, prior, {Eigen::Vector2d::Zero()}, s),
               std::invalid_argument);
  s.ridge_dimensions = -1;
  s.grid_points = 2;
  EXPECT_THROW(runMcmcReference(residual, prior, {Eigen::Vector2d::Zero()}, s),
               std::invalid_argument);
}

// Checks draws of a Gaussian posterior N(mean, cov) within Monte Carlo error:
// the mean within 4 standard errors from the reported ESS; the std within 4
// standard errors sd / sqrt(2 ESS2), ESS2 that of the squared deviations (a
// Hamiltonian chain's ESS of the mean can exceed the draws, its ESS of the
// variance does not); R-hat <= 1.01.
void expectGaussian(const McmcReference& r, const Eigen::VectorXd& mean,
                    const Eigen::MatrixXd& cov) {
  const Eigen::Index chains = static_cast<Eigen::Index>(r.draws.size());
  for (Eigen::Index i = 0; i < mean.size(); ++i) {
    const double sd = std::sqrt(cov(i, i)), ess = r.effective_size[i];
    Eigen::MatrixXd squared(chains, r.draws.front().cols());
    for (Eigen::Index c = 0; c < chains; ++c)
      squared.row(c) = (r.draws[c].row(i).array() - r.xi_mean[i]).square().matrix();
    const double ess2 = effectiveSampleSize(squared);
    EXPECT_NEAR(r.xi_mean[i], mean[i], 4.0 * sd / std::sqrt(ess)) << i;
    EXPECT_NEAR(r.xi_stddev[i], sd, 4.0 * sd / std::sqrt(2.0 * ess2)) << i;
    EXPECT_LE(r.r_hat[i], 1.01) << i;
    EXPECT_GT(ess, 1000.0) << i;
    EXPECT_GT(ess2, 500.0) << i;
  }
}

const char* samplerName(McmcSampler s) {
  switch (s) {
    case McmcSampler::kEnsemble: return "ensemble";
    case McmcSampler::kHamiltonian: return "Hamiltonian";
    case McmcSampler::kConditionalLaplace: return "conditional Laplace";
    default: return "adaptive Metropolis";
  }
}

// Ensemble: 32 walkers (8 n); Hamiltonian: 8 chains; conditional Laplace: 4
// batches of 4000 draws. All well past ESS 1000.
McmcSettings ridgeSettings(McmcSampler sampler) {
  McmcSettings s;
  s.sampler = sampler;
  if (sampler == McmcSampler::kConditionalLaplace) {
    s.chains = 4;
    s.samples = 4000;
    return s;
  }
  s.chains = sampler == McmcSampler::kEnsemble ? 32 : 8;
  s.burn_in = sampler == McmcSampler::kEnsemble ? 1000 : 300;
  s.samples = sampler == McmcSampler::kEnsemble ? 12000 : 2000;
  return s;
}

TEST(McmcSamplers, RecoverA100To1RidgeInFourDimensions) {
  // Prior N(0, I) times a likelihood N(mu, S), S with std 100 along u = (1, 1,
  // 1, 1) / 2 and 0.01 across: the posterior N(P S^-1 mu, P), P = (I + S^-1)^-1,
  // has std 0.99995 along u and 0.0099995 across (ratio 100.0), so every pair
  // of coordinates is correlated 0.9996.
  const Eigen::Vector4d u = Eigen::Vector4d::Constant(0.5);
  const Eigen::Matrix4d across = Eigen::Matrix4d::Identity() - u * u.transpose();
  const Eigen::Matrix4d s = 1e4 * u * u.transpose() + 1e-4 * across;
  const Eigen::Vector4d mu(0.3, 0.31, 0.29, 0.3);
  const LinearResidual residual(mu, s.llt().matrixL(), true);
  // P and S^-1 share S's eigenvectors (a 4 x 4 inverse at condition 1e8 would not be exact).
  const Eigen::Matrix4d p = u * u.transpose() / (1.0 + 1e-4) + across / (1.0 + 1e4);
  const Eigen::Vector4d mean = p * (1e-4 * u * u.transpose() + 1e4 * across) * mu;
  EXPECT_NEAR(std::sqrt(u.dot(p * u) / across.col(0).dot(p * across.col(0)) *
                        across.col(0).squaredNorm()),
              100.0, 1e-9);
  for (const McmcSampler sampler : {McmcSampler::kEnsemble, McmcSampler::kHamiltonian,
                                    McmcSampler::kConditionalLaplace}) {
    McmcSettings settings = ridgeSettings(sampler);
    const std::vector<GermSpec> prior(4, germ(GermFamily::kGaussian));
    const McmcReference r = runMcmcReference(residual, prior, {Eigen::Vector4d::Zero()}, settings);
    expectGaussian(r, mean, p);
    // Correlation: its standard error (1 - rho^2) / sqrt(ESS).
    const double rho = p(0, 1) / std::sqrt(p(0, 0) * p(1, 1));
    const double rho_hat =
        r.xi_covariance(0, 1) / std::sqrt(r.xi_covariance(0, 0) * r.xi_covariance(1, 1));
    EXPECT_NEAR(rho, 0.9996, 1e-4);
    EXPECT_NEAR(rho_hat, rho, 4.0 * (1.0 - rho * rho) / std::sqrt(r.effective_size.minCoeff()));
    EXPECT_GT(r.acceptance, 0.2);
    EXPECT_EQ(r.draws.size(), static_cast<std::size_t>(settings.chains));
    std::printf("4-D ridge, %s: ESS %.0f-%.0f, R-hat <= %.4f, acceptance %.3f, correlation %.6f "
                "(%.6f), %ld evaluations\n",
                samplerName(sampler),
                r.effective_size.minCoeff(), r.effective_size.maxCoeff(), r.r_hat.maxCoeff(),
                r.acceptance, rho_hat, rho, r.simulations);
  }
}

// A load and a scale the readings cannot tell apart, through ModelPosteriorResidual:
// y' = A y + B theta with B's first two columns nearly equal, so only
// theta0 + theta1 is read (their difference to 1e-3 of the data's weight);
// the prior (Gaussian germs) closes the ridge. RK4 is affine in theta, so the
// likelihood is exactly Gaussian in the germs: r(xi) = r0 + G xi, G found from
// n + 1 evaluations, posterior N(-P G^T r0, P), P = (I + G^T G)^-1.
TEST(McmcSamplers, LinearModelWithAScaleRidgeIsTheClosedForm) {
  Eigen::MatrixXd a(2, 2), b(2, 3), c = Eigen::MatrixXd::Identity(2, 2);
  a << 0.0, 1.0, -4.0, -0.4;
  b << 0.0, 0.002, 0.3, 1.0, 1.0, -0.5;
  const testing::LinearForcedModel model(a, b, c, Eigen::Vector3d(1.0, 1.0, 2.0));
  const ParameterMapping mapping(model, {{"theta0", 1.0, 0.5, germ(GermFamily::kGaussian)},
                                         {"theta1", 1.0, 0.5, germ(GermFamily::kGaussian)},
                                         {"theta2", 2.0, 0.2, germ(GermFamily::kGaussian)}});
  std::vector<double> times;
  for (int k = 1; k <= 30; ++k) times.push_back(0.1 * k);
  const IntegratorSettings integration{0.01};
  const auto z = simulateChannels(
      model, mapping.fullParameters(mapping.valuesAtGerms(Eigen::RowVector3d(0.4, -0.2, 0.3))),
      times, integration);
  std::mt19937_64 rng(17);
  std::normal_distribution<double> normal;
  MeasurementSeries series;
  for (std::size_t k = 0; k < times.size(); ++k) {
    series.push_back({times[k], {0, 1}, z[k].col(0).head(2)});
    for (int j = 0; j < 2; ++j) series[k].values[j] += 0.01 * normal(rng);
  }
  const NoiseModel noise{0.0, 1e-4};  // R = 0.01^2 for every reading
  const ModelPosteriorResidual residual(model, mapping, series, noise, integration, 1);
  Eigen::MatrixXd units(3, 4);
  units << 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1;
  const Eigen::MatrixXd rs = residual.residuals(units);
  const Eigen::MatrixXd g = rs.rightCols(3).colwise() - rs.col(0);
  const Eigen::Matrix3d p = (Eigen::Matrix3d::Identity() + g.transpose() * g).inverse();
  const Eigen::Vector3d mean = -p * g.transpose() * rs.col(0);
  // The ridge: theta0 - theta1 is known to the prior's width only.
  const Eigen::Vector3d along(1.0, -1.0, 0.0), sum(1.0, 1.0, 0.0);
  EXPECT_GT(std::sqrt(along.dot(p * along) / sum.dot(p * sum)), 50.0);
  for (const McmcSampler sampler : {McmcSampler::kEnsemble, McmcSampler::kHamiltonian,
                                    McmcSampler::kConditionalLaplace}) {
    McmcSettings settings;
    settings.sampler = sampler;
    settings.chains = sampler == McmcSampler::kEnsemble ? 16 : sampler == McmcSampler::kHamiltonian ? 8 : 4;
    settings.burn_in = sampler == McmcSampler::kEnsemble ? 1000 : 200;
    settings.samples = sampler == McmcSampler::kEnsemble ? 16000 : sampler == McmcSampler::kHamiltonian ? 1500 : 4000;
    const McmcReference r = runMcmcReference(model, mapping, series, noise, integration, 1,
                                             {Eigen::Vector3d::Zero()}, settings);
    std::printf(
        "ridge, %s: mean %.4f %.4f %.4f (closed %.4f %.4f %.4f), std %.4f %.4f %.5f (closed "
        "%.4f %.4f %.5f), ESS %.0f %.0f %.0f, R-hat %.4f, %ld simulations, %.1f s\n",
        samplerName(sampler), r.xi_mean[0],
        r.xi_mean[1], r.xi_mean[2], mean[0], mean[1], mean[2], r.xi_stddev[0], r.xi_stddev[1],
        r.xi_stddev[2], std::sqrt(p(0, 0)), std::sqrt(p(1, 1)), std::sqrt(p(2, 2)),
        r.effective_size[0], r.effective_size[1], r.effective_size[2], r.r_hat.maxCoeff(),
        r.simulations, r.seconds);
    expectGaussian(r, mean, p);
    EXPECT_NEAR(r.mean[0], 1.0 + 0.5 * r.xi_mean[0], 1e-12);  // parameter units
  }
}

// A curved ridge: xi2 follows c xi1^2 to 1e-2 (r = (xi2 - c xi1^2) / sigma),
// Gaussian germs. Integrating xi2 out in closed form leaves
// p(xi1) ∝ exp(-xi1^2 / 2 - c^2 xi1^4 / (2 (1 + sigma^2))), and
// E[xi2 | xi1] = c xi1^2 / (1 + sigma^2), var[xi2 | xi1] = sigma^2 / (1 + sigma^2):
// the moments by quadrature over xi1. No straight proposal covers more than
// a chord of it; the conditional modes follow it.
class CurvedResidual : public PosteriorResidual {
 public:
  CurvedResidual(double c, double sigma) : c_(c), sigma_(sigma) {}
  int dimension() const override { return 2; }
  Eigen::MatrixXd residuals(const Eigen::MatrixXd& xi) const override {
    return ((xi.row(1).array() - c_ * xi.row(0).array().square()) / sigma_).matrix();
  }

 private:
  double c_, sigma_;
};

TEST(McmcSamplers, ConditionalLaplaceFollowsACurvedRidge) {
  const double c = 1.5, sigma = 0.01, v = 1.0 + sigma * sigma;
  double z = 0.0, m1 = 0.0, s1 = 0.0, m2 = 0.0, s2 = 0.0;
  for (int i = -200000; i <= 200000; ++i) {
    const double x = 6e-5 * i, p = std::exp(-0.5 * x * x - 0.5 * c * c * x * x * x * x / v);
    const double e2 = c * x * x / v;
    z += p;
    m1 += p * x;
    s1 += p * x * x;
    m2 += p * e2;
    s2 += p * (e2 * e2 + sigma * sigma / v);
  }
  const Eigen::Vector2d mean(m1 / z, m2 / z);
  const Eigen::Vector2d sd(std::sqrt(s1 / z - mean[0] * mean[0]),
                           std::sqrt(s2 / z - mean[1] * mean[1]));
  const CurvedResidual residual(c, sigma);
  McmcSettings settings = ridgeSettings(McmcSampler::kConditionalLaplace);
  const std::vector<GermSpec> prior(2, germ(GermFamily::kGaussian));
  const McmcReference r = runMcmcReference(residual, prior, {Eigen::Vector2d(0.3, 0.0)}, settings);
  std::printf("curved ridge: mean %.4f %.4f (quadrature %.4f %.4f), std %.4f %.4f (%.4f %.4f), "
              "ESS %.0f %.0f, R-hat %.4f, efficiency %.3f, %d nodes\n",
              r.xi_mean[0], r.xi_mean[1], mean[0], mean[1], r.xi_stddev[0], r.xi_stddev[1],
              sd[0], sd[1], r.effective_size[0], r.effective_size[1], r.r_hat.maxCoeff(),
              r.acceptance, r.ridge_nodes);
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(r.xi_mean[i], mean[i], 4.0 * sd[i] / std::sqrt(r.effective_size[i])) << i;
    EXPECT_NEAR(r.xi_stddev[i], sd[i], 0.05 * sd[i]) << i;
    EXPECT_LE(r.r_hat[i], 1.01) << i;
    EXPECT_GT(r.effective_size[i], 1000.0) << i;
  }
  // The Laplace covariance at the mode misses the curve: xi2's std there is
  // sigma-sized, the posterior's is 10x more. One ridge axis found.
  EXPECT_LT(r.laplace_xi_stddev[1], 0.1 * sd[1]);
  EXPECT_EQ(r.ridge_nodes, 41);
}

// Speed bump, N = 10, 1 % relative noise (test_reference_posterior's case):
// the sampler on the vehicle's likelihood agrees with the grid posterior.
TEST(McmcReference, SpeedBumpAgreesWithTheGridPosterior) {
  const auto model = std::make_shared<RollPlaneModel>(
      VehicleParameters(), std::make_shared<SpeedBumpRoad>(SpeedBumpSettings()));
  const ParameterMapping mapping(*model,
                                 {{"added_mass", 200.0, 0.5, germ(GermFamily::kBeta)},
                                  {"added_mass_position", 0.762, 0.25, germ(GermFamily::kBeta)}});
  const Eigen::Vector2d truth(0.2326, -0.3875);
  std::vector<double> times;
  for (int k = 1; k <= 10; ++k) times.push_back(0.3 * k);
  const IntegratorSettings integration;
  const auto z = simulateChannels(
      *model, mapping.fullParameters(mapping.valuesAtGerms(truth.transpose())), times, integration);
  std::mt19937_64 rng(2008);
  std::normal_distribution<double> normal;
  MeasurementSeries series;
  for (std::size_t k = 0; k < times.size(); ++k) {
    series.push_back({times[k], {0, 1, 2, 3}, z[k].col(0).head(4)});
    for (int j = 0; j < 4; ++j) series[k].values[j] += 0.01 * std::abs(z[k](j, 0)) * normal(rng);
  }
  const NoiseModel noise{0.01, 1e-12};
  ReferencePosteriorSettings grid;
  grid.coarse_points = 41;
  const ReferencePosterior g =
      computeReferencePosterior(*model, mapping, series, noise, integration, grid);
  McmcSettings settings;
  settings.burn_in = 600;
  settings.samples = 2500;
  // The posterior has narrow local maxima besides the global one (the grid
  // posterior's coarse stage exists for that): the mode search starts from a
  // 5 x 5 grid over the prior and the chains sample the best basin.
  std::vector<Eigen::VectorXd> starts;
  for (double a : {-0.8, -0.4, 0.0, 0.4, 0.8}) {
    for (double b : {-0.8, -0.4, 0.0, 0.4, 0.8}) starts.push_back(Eigen::Vector2d(a, b));
  }
  McmcSettings importance;
  importance.sampler = McmcSampler::kConditionalLaplace;
  importance.chains = 4;
  importance.samples = 2000;
  for (const McmcSettings& ms : {settings, importance}) {
  const McmcReference r =
      runMcmcReference(*model, mapping, series, noise, integration, 2, starts, ms);
  std::printf(
      "%s: grid M %.4f +- %.4f, d %.6f +- %.6f; sampled M %.4f +- %.4f (mcse %.4f), d %.6f +- %.6f "
      "(mcse %.6f); ESS %.0f %.0f, R-hat %.4f %.4f, %ld simulations, %.1f s\n",
      samplerName(ms.sampler), g.mean[0], g.stddev[0], g.mean[1], g.stddev[1], r.mean[0], r.stddev[0], r.mean_error[0],
      r.mean[1], r.stddev[1], r.mean_error[1], r.effective_size[0], r.effective_size[1], r.r_hat[0],
      r.r_hat[1], r.simulations, r.seconds);
  EXPECT_EQ(r.names, g.names);
  ASSERT_EQ(g.modes.size(), 1u);
  EXPECT_NEAR(r.mode_log_density, g.modes[0].log_density, 1e-6 * std::abs(g.modes[0].log_density));
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(r.mean[i], g.mean[i], 5.0 * r.mean_error[i] + 0.01 * g.stddev[i]) << i;
    EXPECT_NEAR(r.stddev[i], g.stddev[i], 0.1 * g.stddev[i]) << i;
    EXPECT_LT(r.r_hat[i], 1.05) << i;
    EXPECT_GT(r.effective_size[i], 400.0) << i;
  }
  }
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
