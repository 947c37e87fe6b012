// Reference posterior (docs/method.md §4.6): synthetic likelihoods with independently
// known answers (closed forms, 1-D quadrature), then the speed-bump case.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <random>

#include "pc_ekf/reference/posterior_prior.h"
#include "linear_residual.h"
#include "pc_ekf/reference/reference_posterior.h"
#include "pc_ekf/filter/trajectory_simulation.h"
#include "pc_ekf/model/roll_plane_model.h"

namespace pc_ekf {
namespace {

GermSpec germ(GermFamily family, double alpha = 2.0, double beta = 2.0) {
  GermSpec g;
  g.family = family;
  g.alpha = alpha;
  g.beta = beta;
  return g;
}

using testing::LinearResidual;

// r1 = (xi1^2 - 1/4) / 0.01 (modes near +-1/2), r2 = (xi2 - 0.1) / 0.05.
class TwoModeResidual : public PosteriorResidual {
 public:
  int dimension() const override { return 2; }
  Eigen::MatrixXd residuals(const Eigen::MatrixXd& xi) const override {
    Eigen::MatrixXd r(2, xi.cols());
    r.row(0) = (xi.row(0).array().square() - 0.25) / 0.01;
    r.row(1) = (xi.row(1).array() - 0.1) / 0.05;
    return r;
  }
};

// Sum over bins of density x width x f(centre).
double histogramIntegral(const Histogram& h, double power) {
  const Eigen::Index b = h.densities.size();
  const Eigen::ArrayXd width = h.edges.tail(b) - h.edges.head(b);
  return (h.centres().array().pow(power) * h.densities.array() * width).sum();
}
double histogramArea(const Histogram& h) { return histogramIntegral(h, 0.0); }
double histogramMean(const Histogram& h) { return histogramIntegral(h, 1.0); }

TEST(ReferencePosterior, LinearGaussianGivesMeanCovarianceAndEvidence) {
  const Eigen::Vector2d mu(0.3, -0.2);
  const Eigen::Vector2d sigma(1e-3, 2e-3);  // correlation 0.6
  Eigen::Matrix2d cov;
  cov << 1e-6, 1.2e-6, 1.2e-6, 4e-6;
  const LinearResidual residual(mu, cov.llt().matrixL());
  const ReferencePosterior r =
      computeReferencePosterior(residual, {germ(GermFamily::kUniform), germ(GermFamily::kUniform)},
                                ReferencePosteriorSettings());
  ASSERT_EQ(r.modes.size(), 1u);
  EXPECT_NEAR(r.modes[0].mass_fraction, 1.0, 1e-15);
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(r.xi_mean[i], mu[i], 1e-3 * sigma[i]);
    EXPECT_NEAR(r.xi_stddev[i], sigma[i], 1e-3 * sigma[i]);
    EXPECT_NEAR(r.modes[0].xi[i], mu[i], 1e-6 * sigma[i]);
    EXPECT_NEAR(histogramArea(r.marginals[i]), 1.0, 1e-12);
    EXPECT_NEAR(histogramMean(r.marginals[i]), mu[i], 0.02 * sigma[i]);
  }
  EXPECT_NEAR(r.xi_covariance(0, 1), cov(0, 1), 1e-3 * cov(0, 1));
  // Uniform prior density 1/4 times the Gaussian integral 2 pi sqrt(det).
  EXPECT_NEAR(r.log_mass, std::log(0.25 * 2.0 * M_PI * std::sqrt(cov.determinant())), 1e-6);
  EXPECT_LT(r.border_mass, 1e-6);
  EXPECT_EQ(r.coarse_grid_size, 101 * 101);
  EXPECT_EQ(r.simulations, 0);
}

TEST(ReferencePosterior, GaussianPriorTimesGaussianLikelihoodInOneDimension) {
  // Prior N(0, 1), likelihood N(1, 0.5^2): posterior N(0.8, 0.2) exactly.
  const LinearResidual residual(Eigen::VectorXd::Constant(1, 1.0),
                                Eigen::MatrixXd::Constant(1, 1, 0.5));
  const ReferencePosterior r = computeReferencePosterior(residual, {germ(GermFamily::kGaussian)},
                                                         ReferencePosteriorSettings());
  ASSERT_EQ(r.modes.size(), 1u);
  EXPECT_NEAR(r.modes[0].xi[0], 0.8, 1e-6);
  EXPECT_NEAR(r.xi_mean[0], 0.8, 1e-9);
  EXPECT_NEAR(r.xi_stddev[0], std::sqrt(0.2), 1e-9);
  // Evidence: N(1; 0, 1 + 0.25) * sqrt(2 pi) * 0.5 (the likelihood lacks its constant).
  const double evidence =
      std::exp(-0.5 / 1.25) / std::sqrt(2.0 * M_PI * 1.25) * std::sqrt(2.0 * M_PI) * 0.5;
  EXPECT_NEAR(r.log_mass, std::log(evidence), 1e-8);
}

TEST(ReferencePosterior, ANarrowRidgeWithManyCoarseMaximaIsOneMode) {
  // xi2 = 0.5 xi1 + 0.1 within 1e-3, xi1 = 0 +- 0.15: a ridge the 0.02-spaced
  // coarse grid aliases into many local maxima. Posterior Gaussian (the
  // uniform prior's edges are 6.7 std away): xi1 ~ N(0, s^2),
  // xi2 ~ N(0.1, 0.25 s^2 + 1e-6), covariance 0.5 s^2.
  const double s = 0.15;
  Eigen::Matrix2d inverse_l;  // r = inverse_l * (xi - mu)
  inverse_l << 1.0 / s, 0.0, -0.5 / 1e-3, 1.0 / 1e-3;
  const LinearResidual residual(Eigen::Vector2d(0.0, 0.1), inverse_l.inverse());
  const ReferencePosterior r =
      computeReferencePosterior(residual, {germ(GermFamily::kUniform), germ(GermFamily::kUniform)},
                                ReferencePosteriorSettings());
  std::printf("ridge: %d coarse maxima, %d refined, %zu mode(s)\n", r.coarse_local_maxima,
              r.refined_candidates, r.modes.size());
  EXPECT_GT(r.coarse_local_maxima, 3);
  ASSERT_EQ(r.modes.size(), 1u);
  const double s2 = std::sqrt(0.25 * s * s + 1e-6);
  EXPECT_NEAR(r.xi_mean[0], 0.0, 1e-4 * s);
  EXPECT_NEAR(r.xi_mean[1], 0.1, 1e-4 * s2);
  EXPECT_NEAR(r.xi_stddev[0], s, 1e-4 * s);
  EXPECT_NEAR(r.xi_stddev[1], s2, 1e-4 * s2);
  EXPECT_NEAR(r.xi_covariance(0, 1), 0.5 * s * s, 1e-4 * s * s2);
}

// Composite Simpson of f on [a, b] with an even number of intervals.
double simpson(const std::function<double(double)>& f, double a, double b, int intervals) {
  const double h = (b - a) / intervals;
  double s = f(a) + f(b);
  for (int i = 1; i < intervals; ++i) s += f(a + i * h) * (i % 2 ? 4.0 : 2.0);
  return s * h / 3.0;
}

TEST(ReferencePosterior, TwoModesGetTheirQuadratureMasses) {
  // Prior Beta(3,2) x Beta(2,2): w1 ~ (1+x)^2 (1-x) weighs the mode at +1/2
  // about three times the one at -1/2. The posterior factorises, so 1-D
  // quadrature gives every expected number.
  const GermSpec g1 = germ(GermFamily::kBeta, 3.0, 2.0), g2 = germ(GermFamily::kBeta);
  const auto p1 = [](double x) {
    const double r = (x * x - 0.25) / 0.01;
    return (1 + x) * (1 + x) * (1 - x) * std::exp(-0.5 * r * r);
  };
  const auto p2 = [](double y) {
    const double r = (y - 0.1) / 0.05;
    return (1 - y * y) * std::exp(-0.5 * r * r);
  };
  const int q = 400000;
  const double right = simpson(p1, 0.0, 1.0, q), left = simpson(p1, -1.0, 0.0, q);
  const double m1 = simpson([&](double x) { return x * p1(x); }, -1, 1, q) / (left + right);
  const double v1 =
      simpson([&](double x) { return (x - m1) * (x - m1) * p1(x); }, -1, 1, q) / (left + right);
  const double z2 = simpson(p2, -1, 1, q);
  const double m2 = simpson([&](double y) { return y * p2(y); }, -1, 1, q) / z2;
  const double v2 = simpson([&](double y) { return (y - m2) * (y - m2) * p2(y); }, -1, 1, q) / z2;

  const TwoModeResidual residual;
  const ReferencePosterior r =
      computeReferencePosterior(residual, {g1, g2}, ReferencePosteriorSettings());
  ASSERT_EQ(r.modes.size(), 2u);
  std::printf("masses %.8f %.8f, quadrature %.8f\n", r.modes[0].mass_fraction,
              r.modes[1].mass_fraction, right / (left + right));
  EXPECT_GT(r.coarse_local_maxima, 1);
  EXPECT_NEAR(r.modes[0].mass_fraction, right / (left + right), 1e-3);
  EXPECT_NEAR(r.modes[1].mass_fraction, left / (left + right), 1e-3);
  EXPECT_GT(r.modes[0].mass_fraction, 0.7);  // really unequal (expected ~0.75)
  EXPECT_NEAR(r.modes[0].xi[0], 0.5, 0.01);
  EXPECT_NEAR(r.modes[1].xi[0], -0.5, 0.01);
  EXPECT_NEAR(r.xi_mean[0], m1, 1e-4 * std::sqrt(v1));
  EXPECT_NEAR(r.xi_stddev[0], std::sqrt(v1), 1e-4 * std::sqrt(v1));
  EXPECT_NEAR(r.xi_mean[1], m2, 1e-4 * std::sqrt(v2));
  EXPECT_NEAR(r.xi_stddev[1], std::sqrt(v2), 1e-4 * std::sqrt(v2));
  EXPECT_LT(r.border_mass, 1e-6);
  EXPECT_NEAR(histogramArea(r.marginals[0]), 1.0, 1e-12);
  EXPECT_NEAR(histogramMean(r.marginals[0]), m1, 0.01);  // both modes binned
}

TEST(ReferencePosterior, WhitenedResidualsUseTheFiltersNoise) {
  MeasurementSeries series(2);
  series[0].time = 0.1;
  series[0].channels = {0, 2};
  series[0].values = Eigen::Vector2d(0.5, -2.0);
  series[1].time = 0.2;
  series[1].channels = {1};
  series[1].values = Eigen::VectorXd::Constant(1, 0.0);  // R falls to the floor
  const NoiseModel noise{0.01, 1e-12};
  std::vector<Eigen::MatrixXd> channels(2, Eigen::MatrixXd::Zero(3, 2));
  channels[0].col(0) << 0.49, 7.0, -2.04;
  channels[0].col(1) << 0.5, 7.0, std::nan("");
  channels[1].col(0) << 0.0, 3e-6, 0.0;
  channels[1].col(1) << 0.0, -1e-6, 0.0;
  const Eigen::MatrixXd r = whitenedResiduals(series, noise, channels);
  ASSERT_EQ(r.rows(), 3);
  EXPECT_NEAR(r(0, 0), 0.01 / 0.005, 1e-12);
  EXPECT_NEAR(r(1, 0), 0.04 / 0.02, 1e-12);
  EXPECT_NEAR(r(2, 0), -3e-6 / 1e-6, 1e-9);
  EXPECT_NEAR(r(2, 1), 1.0, 1e-9);
  const Eigen::VectorXd ll = logLikelihood(r);
  EXPECT_NEAR(ll[0], -0.5 * (4.0 + 4.0 + 9.0), 1e-8);
  EXPECT_TRUE(std::isinf(ll[1]) && ll[1] < 0.0);  // a NaN channel: zero likelihood
}

struct VehicleCase {
  std::shared_ptr<RollPlaneModel> model;
  std::unique_ptr<ParameterMapping> mapping;
  MeasurementSeries series;
  NoiseModel noise{0.01, 1e-12};
  IntegratorSettings integration;
  Eigen::Vector2d truth{0.2326, -0.3875};
};

// Standard normal from raw 64-bit draws (Box-Muller): the same on every library.
double normal(std::mt19937_64& rng) {
  const double u1 = (static_cast<double>(rng() >> 11) + 0.5) * 0x1.0p-53;
  const double u2 = (static_cast<double>(rng() >> 11) + 0.5) * 0x1.0p-53;
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

// Synthetic data of docs/method.md §1.6: N samples over 3 s, 1 % relative noise.
VehicleCase makeCase(std::shared_ptr<const ContactRoad> road, int samples, std::uint64_t seed) {
  VehicleCase c;
  c.model = std::make_shared<RollPlaneModel>(VehicleParameters(), std::move(road));
  c.mapping = std::make_unique<ParameterMapping>(
      *c.model, std::vector<UncertainParameter>{
                    {"added_mass", 200.0, 0.5, germ(GermFamily::kBeta)},
                    {"added_mass_position", 0.762, 0.25, germ(GermFamily::kBeta)}});
  std::vector<double> times;
  for (int k = 1; k <= samples; ++k) times.push_back(3.0 * k / samples);
  const Eigen::MatrixXd params =
      c.mapping->fullParameters(c.mapping->valuesAtGerms(c.truth.transpose()));
  const auto z = simulateChannels(*c.model, params, times, c.integration);
  std::mt19937_64 rng(seed);
  for (std::size_t k = 0; k < times.size(); ++k) {
    c.series.push_back({times[k], {0, 1, 2, 3}, z[k].col(0).head(4)});
    for (int j = 0; j < 4; ++j) c.series[k].values[j] += 0.01 * std::abs(z[k](j, 0)) * normal(rng);
  }
  return c;
}

// docs/method.md §1.6 case N = 10 on a 41 x 41 coarse grid (cached once), fine grids 33
// and 65, and the same without the cache; computed once for all tests.
struct SpeedBumpRuns {
  static constexpr int kCoarse = 41;
  VehicleCase bump = makeCase(std::make_shared<SpeedBumpRoad>(SpeedBumpSettings()), 10, 2008);
  std::unique_ptr<CoarseGridCache> cache;
  ReferencePosterior uncached, fine33, fine65;

  SpeedBumpRuns() {
    ReferencePosteriorSettings s;
    s.coarse_points = kCoarse;
    cache = std::make_unique<CoarseGridCache>(*bump.model, *bump.mapping, sampleTimes(bump.series),
                                              bump.integration, kCoarse, s.threads);
    uncached = run(s, nullptr);
    fine33 = run(s, cache.get());
    s.fine_points = 65;
    fine65 = run(s, cache.get());
  }
  ReferencePosterior run(const ReferencePosteriorSettings& s, const CoarseGridCache* c) const {
    const ReferencePosterior r = computeReferencePosterior(*bump.model, *bump.mapping, bump.series,
                                                           bump.noise, bump.integration, s, c);
    std::printf(
        "fine %d%s: xi mean (%.9f, %.9f) std (%.6e, %.6e); M = %.4f +- %.4f kg, d = %.6f +- "
        "%.6f m; %zu mode(s), border %.1e, %ld simulations (+%ld cached); coarse %.2f s, "
        "refine %.2f s, fine %.2f s, total %.2f s\n",
        s.fine_points, c ? " cached" : "", r.xi_mean[0], r.xi_mean[1], r.xi_stddev[0],
        r.xi_stddev[1], r.mean[0], r.stddev[0], r.mean[1], r.stddev[1], r.modes.size(),
        r.border_mass, r.simulations, r.cached_simulations, r.coarse_seconds, r.refine_seconds,
        r.fine_seconds, r.total_seconds);
    return r;
  }
};

const SpeedBumpRuns& speedBump() {
  static const SpeedBumpRuns runs;
  return runs;
}

TEST(SpeedBumpPosterior, FineGridRefinementChangesMeanAndStdByUnderOnePercentOfStd) {
  const SpeedBumpRuns& b = speedBump();
  for (int i = 0; i < 2; ++i) {
    const double s = b.fine65.xi_stddev[i];
    EXPECT_LT(std::abs(b.fine33.xi_mean[i] - b.fine65.xi_mean[i]), 0.01 * s) << i;
    EXPECT_LT(std::abs(b.fine33.xi_stddev[i] - s), 0.01 * s) << i;
  }
}

TEST(SpeedBumpPosterior, MeanLiesWithinAFewStdOfTheTruth) {
  const SpeedBumpRuns& b = speedBump();
  const ReferencePosterior& r = b.fine33;
  ASSERT_FALSE(r.modes.empty());
  EXPECT_GT(r.modes[0].mass_fraction, 0.5);
  for (int i = 0; i < 2; ++i) {
    EXPECT_LT(std::abs(r.xi_mean[i] - b.bump.truth[i]), 4.0 * r.xi_stddev[i]) << i;
    // 1 % noise on 40 values: narrow, yet far wider than round-off (docs/method.md §4.6).
    EXPECT_GT(r.xi_stddev[i], 1e-5);
    EXPECT_LT(r.xi_stddev[i], 0.05);
    EXPECT_NEAR(histogramArea(r.marginals[i]), 1.0, 1e-12);
    EXPECT_NEAR(histogramMean(r.marginals[i]), r.mean[i], 0.05 * r.stddev[i]);
  }
  EXPECT_NEAR(r.mean[0], 200.0 * (1.0 + 0.5 * r.xi_mean[0]), 1e-9);
  EXPECT_NEAR(r.stddev[1], 0.762 * 0.25 * r.xi_stddev[1], 1e-12);
  EXPECT_EQ(r.names[0], "added_mass");
  EXPECT_LT(r.border_mass, 1e-6);
  EXPECT_GT(b.uncached.simulations, b.uncached.coarse_grid_size);
}

TEST(SpeedBumpPosterior, CacheReproducesTheUncachedRunWithoutCoarseSimulations) {
  const SpeedBumpRuns& b = speedBump();
  EXPECT_EQ(b.fine33.cached_simulations, b.cache->simulations());
  EXPECT_EQ(b.uncached.simulations - b.fine33.simulations, b.cache->simulations());
  // Beta(2,2) has zero density on the grid's edge: only interior nodes run.
  EXPECT_EQ(b.cache->simulations(), (SpeedBumpRuns::kCoarse - 2) * (SpeedBumpRuns::kCoarse - 2));
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(b.fine33.xi_mean[i], b.uncached.xi_mean[i], 1e-12);
    EXPECT_NEAR(b.fine33.xi_stddev[i], b.uncached.xi_stddev[i], 1e-12);
  }
  // A cache is only valid for its sample times and grid.
  ReferencePosteriorSettings s;
  s.coarse_points = SpeedBumpRuns::kCoarse;
  MeasurementSeries shorter(b.bump.series.begin(), b.bump.series.end() - 1);
  EXPECT_THROW(computeReferencePosterior(*b.bump.model, *b.bump.mapping, shorter, b.bump.noise,
                                         b.bump.integration, s, b.cache.get()),
               std::invalid_argument);
  s.coarse_points = SpeedBumpRuns::kCoarse + 2;
  EXPECT_THROW(computeReferencePosterior(*b.bump.model, *b.bump.mapping, b.bump.series,
                                         b.bump.noise, b.bump.integration, s, b.cache.get()),
               std::invalid_argument);
}

TEST(SpeedBumpPosterior, AgreesWithABruteForceAxisAlignedGrid) {
  const SpeedBumpRuns& b = speedBump();
  // Independent of the mode search and the principal axes: 81 x 81 nodes over
  // mean +- 7 marginal std, plain sums (the density at the box edge is ~e^-24).
  const ReferencePosterior& r = b.fine33;
  const ModelPosteriorResidual residual(*b.bump.model, *b.bump.mapping, b.bump.series, b.bump.noise,
                                        b.bump.integration, 2);
  const PriorDensity prior(b.bump.mapping->germs());
  const int p = 81;
  Eigen::MatrixXd xi(2, p * p);
  for (int i = 0; i < p; ++i) {
    for (int j = 0; j < p; ++j) {
      xi(0, i + p * j) = r.xi_mean[0] + r.xi_stddev[0] * (-7.0 + 14.0 * i / (p - 1));
      xi(1, i + p * j) = r.xi_mean[1] + r.xi_stddev[1] * (-7.0 + 14.0 * j / (p - 1));
    }
  }
  const Eigen::VectorXd l = prior.logDensities(xi) + logLikelihood(residual.residuals(xi));
  const Eigen::VectorXd w = (l.array() - l.maxCoeff()).exp().matrix();
  const Eigen::Vector2d mean = xi * w / w.sum();
  const Eigen::MatrixXd centred = xi.colwise() - mean;
  const Eigen::Vector2d var = centred.cwiseAbs2() * w / w.sum();
  std::printf("brute force: mean (%.9f, %.9f) std (%.6e, %.6e)\n", mean[0], mean[1],
              std::sqrt(var[0]), std::sqrt(var[1]));
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(mean[i], r.xi_mean[i], 0.01 * r.xi_stddev[i]) << i;
    EXPECT_NEAR(std::sqrt(var[i]), r.xi_stddev[i], 0.005 * r.xi_stddev[i]) << i;
  }
}

// Full 101 x 101 grids on the paper's inputs (docs/method.md §6), for timing reports:
// run with --gtest_also_run_disabled_tests.
TEST(ReferencePosteriorReport, DISABLED_PaperInputs) {
  const auto bump = std::make_shared<SpeedBumpRoad>(SpeedBumpSettings());
  const auto sine = std::make_shared<SineRoad>(SineSettings());
  const struct {
    const char* name;
    std::shared_ptr<const ContactRoad> road;
    int samples;
  } cases[] = {{"bump N=10", bump, 10},
               {"bump N=100", bump, 100},
               {"sine N=10", sine, 10},
               {"sine N=100", sine, 100}};
  for (const auto& k : cases) {
    const VehicleCase c = makeCase(k.road, k.samples, 2008);
    const ReferencePosterior r = computeReferencePosterior(
        *c.model, *c.mapping, c.series, c.noise, c.integration, ReferencePosteriorSettings());
    std::printf(
        "%s: xi mean (%.6f, %.6f) std (%.3e, %.3e); %zu mode(s) of %d maxima, heaviest "
        "%.4f; border %.1e; %ld simulations; coarse %.2f s, refine %.2f s, fine %.2f s, "
        "total %.2f s\n",
        k.name, r.xi_mean[0], r.xi_mean[1], r.xi_stddev[0], r.xi_stddev[1], r.modes.size(),
        r.coarse_local_maxima, r.modes[0].mass_fraction, r.border_mass, r.simulations,
        r.coarse_seconds, r.refine_seconds, r.fine_seconds, r.total_seconds);
    EXPECT_LT(r.border_mass, 1e-6) << k.name;
    for (int i = 0; i < 2; ++i) {
      EXPECT_LT(std::abs(r.xi_mean[i] - c.truth[i]), 5.0 * r.xi_stddev[i]) << k.name;
    }
  }
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
