// Reference posterior (SPEC §3.5): synthetic likelihoods with independently
// known answers (closed forms, 1-D quadrature), then the speed-bump case.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <random>

#include "filter/posterior_prior.h"
#include "filter/reference_posterior.h"
#include "filter/trajectory_simulation.h"
#include "model/roll_plane_model.h"

namespace pc_ekf {
namespace {

GermSpec germ(GermFamily family, double alpha = 2.0, double beta = 2.0) {
  GermSpec g;
  g.family = family;
  g.alpha = alpha;
  g.beta = beta;
  return g;
}

// r = L^-1 (xi - mu): likelihood N(mu, L L^T).
class LinearResidual : public PosteriorResidual {
 public:
  LinearResidual(Eigen::VectorXd mu, Eigen::MatrixXd chol) : mu_(std::move(mu)), l_(std::move(chol)) {}
  int dimension() const override { return static_cast<int>(mu_.size()); }
  Eigen::MatrixXd residuals(const Eigen::MatrixXd& xi) const override {
    return l_.triangularView<Eigen::Lower>().solve(xi.colwise() - mu_);
  }
 private:
  Eigen::VectorXd mu_;
  Eigen::MatrixXd l_;
};

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

double histogramArea(const Histogram& h) {
  return (h.densities.array() * (h.edges.tail(h.densities.size()) - h.edges.head(h.densities.size())).array()).sum();
}

double histogramMean(const Histogram& h) {
  const Eigen::Index b = h.densities.size();
  const Eigen::ArrayXd width = h.edges.tail(b) - h.edges.head(b);
  return (h.centres().array() * h.densities.array() * width).sum();
}

TEST(ReferencePosterior, LinearGaussianGivesMeanCovarianceAndEvidence) {
  const Eigen::Vector2d mu(0.3, -0.2);
  const Eigen::Vector2d sigma(1e-3, 2e-3);
  const double rho = 0.6;
  Eigen::Matrix2d cov;
  cov << sigma[0] * sigma[0], rho * sigma[0] * sigma[1], rho * sigma[0] * sigma[1],
      sigma[1] * sigma[1];
  const LinearResidual residual(mu, cov.llt().matrixL());
  const ReferencePosterior r = computeReferencePosterior(
      residual, {germ(GermFamily::kUniform), germ(GermFamily::kUniform)},
      ReferencePosteriorSettings());
  ASSERT_EQ(r.modes.size(), 1u);
  std::printf("mean %.9g %.9g std %.9g %.9g log mass %.12g\n", r.xi_mean[0], r.xi_mean[1],
              r.xi_stddev[0], r.xi_stddev[1], r.log_mass);
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
  const ReferencePosterior r =
      computeReferencePosterior(residual, {germ(GermFamily::kGaussian)}, ReferencePosteriorSettings());
  ASSERT_EQ(r.modes.size(), 1u);
  EXPECT_NEAR(r.modes[0].xi[0], 0.8, 1e-6);
  EXPECT_NEAR(r.xi_mean[0], 0.8, 1e-9);
  EXPECT_NEAR(r.xi_stddev[0], std::sqrt(0.2), 1e-9);
  // Evidence: N(1; 0, 1 + 0.25) * sqrt(2 pi) * 0.5 (the likelihood lacks its constant).
  const double evidence = std::exp(-0.5 / 1.25) / std::sqrt(2.0 * M_PI * 1.25) *
                          std::sqrt(2.0 * M_PI) * 0.5;
  EXPECT_NEAR(r.log_mass, std::log(evidence), 1e-8);
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
  const ReferencePosterior r = computeReferencePosterior(residual, {g1, g2}, ReferencePosteriorSettings());
  ASSERT_EQ(r.modes.size(), 2u);
  std::printf("masses %.8f %.8f (quadrature %.8f), mean %.8f (%.8f), std %.8f (%.8f), %ld\n",
              r.modes[0].mass_fraction, r.modes[1].mass_fraction, right / (left + right),
              r.xi_mean[0], m1, r.xi_stddev[0], std::sqrt(v1), r.simulations);
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
  // Both modes show in the marginal of xi1: little density between them.
  const Histogram& h = r.marginals[0];
  EXPECT_NEAR(histogramArea(h), 1.0, 1e-12);
  EXPECT_NEAR(histogramMean(h), m1, 0.01);
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

// ---- The speed-bump case of SPEC §1.6, N = 10 -------------------------------

struct SpeedBumpCase {
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

SpeedBumpCase makeSpeedBumpCase(std::uint64_t seed) {
  SpeedBumpCase c;
  c.model = std::make_shared<RollPlaneModel>(VehicleParameters(),
                                             std::make_shared<SpeedBumpRoad>(SpeedBumpSettings()));
  c.mapping = std::make_unique<ParameterMapping>(
      *c.model, std::vector<UncertainParameter>{{"added_mass", 200.0, 0.5, germ(GermFamily::kBeta)},
                                                {"added_mass_position", 0.762, 0.25,
                                                 germ(GermFamily::kBeta)}});
  std::vector<double> times;
  for (int k = 1; k <= 10; ++k) times.push_back(0.3 * k);
  const Eigen::MatrixXd params =
      c.mapping->fullParameters(c.mapping->valuesAtGerms(c.truth.transpose()));
  const auto z = simulateChannels(*c.model, params, times, c.integration);
  std::mt19937_64 rng(seed);
  for (std::size_t k = 0; k < times.size(); ++k) {
    Measurement m;
    m.time = times[k];
    m.channels = {0, 1, 2, 3};
    m.values = z[k].col(0);
    for (int j = 0; j < 4; ++j) m.values[j] += 0.01 * std::abs(z[k](j, 0)) * normal(rng);
    c.series.push_back(m);
  }
  return c;
}

class SpeedBumpPosterior : public ::testing::Test {
 protected:
  static constexpr int kCoarse = 41;
  static void SetUpTestSuite() {
    bump_ = new SpeedBumpCase(makeSpeedBumpCase(2008));
    ReferencePosteriorSettings s;
    s.coarse_points = kCoarse;
    const auto t0 = std::chrono::steady_clock::now();
    cache_ = new CoarseGridCache(*bump_->model, *bump_->mapping, sampleTimes(bump_->series),
                                 bump_->integration, kCoarse, s.threads);
    const auto t1 = std::chrono::steady_clock::now();
    std::printf("coarse cache %dx%d: %ld simulations, %.2f s\n", kCoarse, kCoarse,
                cache_->simulations(), std::chrono::duration<double>(t1 - t0).count());
    uncached_ = new ReferencePosterior(compute(s, nullptr));
    coarse33_ = new ReferencePosterior(compute(s, cache_));
    s.fine_points = 65;
    fine65_ = new ReferencePosterior(compute(s, cache_));
  }
  static void TearDownTestSuite() {
    delete fine65_;
    delete coarse33_;
    delete uncached_;
    delete cache_;
    delete bump_;
  }
  static ReferencePosterior compute(const ReferencePosteriorSettings& s,
                                    const CoarseGridCache* cache) {
    const ReferencePosterior r = computeReferencePosterior(
        *bump_->model, *bump_->mapping, bump_->series, bump_->noise, bump_->integration, s, cache);
    std::printf(
        "fine %d%s: xi mean (%.6f, %.6f) std (%.3e, %.3e); M = %.4f +- %.4f kg, d = %.6f +- "
        "%.6f m; %zu mode(s), border %.1e, %ld simulations (+%ld cached), coarse %.2f s, "
        "refine %.2f s, fine %.2f s, total %.2f s\n",
        s.fine_points, cache ? " cached" : "", r.xi_mean[0], r.xi_mean[1], r.xi_stddev[0],
        r.xi_stddev[1], r.mean[0], r.stddev[0], r.mean[1], r.stddev[1], r.modes.size(),
        r.border_mass, r.simulations, r.cached_simulations, r.coarse_seconds, r.refine_seconds,
        r.fine_seconds, r.total_seconds);
    return r;
  }
  static SpeedBumpCase* bump_;
  static CoarseGridCache* cache_;
  static ReferencePosterior *uncached_, *coarse33_, *fine65_;
};
SpeedBumpCase* SpeedBumpPosterior::bump_ = nullptr;
CoarseGridCache* SpeedBumpPosterior::cache_ = nullptr;
ReferencePosterior* SpeedBumpPosterior::uncached_ = nullptr;
ReferencePosterior* SpeedBumpPosterior::coarse33_ = nullptr;
ReferencePosterior* SpeedBumpPosterior::fine65_ = nullptr;

TEST_F(SpeedBumpPosterior, FineGridRefinementChangesMeanAndStdByUnderOnePercentOfStd) {
  std::printf("33 -> 65: mean (%.9f, %.9f) -> (%.9f, %.9f), std (%.6e, %.6e) -> (%.6e, %.6e)\n",
              coarse33_->xi_mean[0], coarse33_->xi_mean[1], fine65_->xi_mean[0],
              fine65_->xi_mean[1], coarse33_->xi_stddev[0], coarse33_->xi_stddev[1],
              fine65_->xi_stddev[0], fine65_->xi_stddev[1]);
  for (int i = 0; i < 2; ++i) {
    const double s = fine65_->xi_stddev[i];
    EXPECT_LT(std::abs(coarse33_->xi_mean[i] - fine65_->xi_mean[i]), 0.01 * s) << i;
    EXPECT_LT(std::abs(coarse33_->xi_stddev[i] - s), 0.01 * s) << i;
  }
}

TEST_F(SpeedBumpPosterior, MeanLiesWithinAFewStdOfTheTruth) {
  const ReferencePosterior& r = *coarse33_;
  ASSERT_FALSE(r.modes.empty());
  EXPECT_GT(r.modes[0].mass_fraction, 0.5);
  for (int i = 0; i < 2; ++i) {
    EXPECT_LT(std::abs(r.xi_mean[i] - bump_->truth[i]), 4.0 * r.xi_stddev[i]) << i;
    // 1 % noise on 40 values: narrow, yet far wider than round-off (SPEC §3.5).
    EXPECT_GT(r.xi_stddev[i], 1e-5);
    EXPECT_LT(r.xi_stddev[i], 0.05);
    EXPECT_NEAR(histogramArea(r.marginals[i]), 1.0, 1e-12);
    EXPECT_NEAR(histogramMean(r.marginals[i]), r.mean[i], 0.05 * r.stddev[i]);
  }
  EXPECT_NEAR(r.mean[0], 200.0 * (1.0 + 0.5 * r.xi_mean[0]), 1e-9);
  EXPECT_NEAR(r.stddev[1], 0.762 * 0.25 * r.xi_stddev[1], 1e-12);
  EXPECT_EQ(r.names[0], "added_mass");
  EXPECT_LT(r.border_mass, 1e-6);
  EXPECT_GT(uncached_->simulations, uncached_->coarse_grid_size);
}

TEST_F(SpeedBumpPosterior, CacheReproducesTheUncachedRunWithoutCoarseSimulations) {
  EXPECT_EQ(coarse33_->cached_simulations, cache_->simulations());
  EXPECT_EQ(uncached_->simulations - coarse33_->simulations, cache_->simulations());
  // Beta(2,2) has zero density on the grid's edge: only interior nodes run.
  EXPECT_EQ(cache_->simulations(), (kCoarse - 2) * (kCoarse - 2));
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(coarse33_->xi_mean[i], uncached_->xi_mean[i], 1e-12);
    EXPECT_NEAR(coarse33_->xi_stddev[i], uncached_->xi_stddev[i], 1e-12);
  }
  // A cache is only valid for its sample times and grid.
  ReferencePosteriorSettings s;
  s.coarse_points = kCoarse;
  MeasurementSeries shorter(bump_->series.begin(), bump_->series.end() - 1);
  EXPECT_THROW(computeReferencePosterior(*bump_->model, *bump_->mapping, shorter, bump_->noise,
                                         bump_->integration, s, cache_),
               std::invalid_argument);
  s.coarse_points = kCoarse + 2;
  EXPECT_THROW(computeReferencePosterior(*bump_->model, *bump_->mapping, bump_->series,
                                         bump_->noise, bump_->integration, s, cache_),
               std::invalid_argument);
}

TEST_F(SpeedBumpPosterior, AgreesWithABruteForceAxisAlignedGrid) {
  // Independent of the mode search and the principal axes: 81 x 81 nodes over
  // mean +- 7 marginal std, plain sums (the density at the box edge is ~e^-24).
  const ReferencePosterior& r = *coarse33_;
  const ModelPosteriorResidual residual(*bump_->model, *bump_->mapping, bump_->series,
                                        bump_->noise, bump_->integration, 2);
  const PriorDensity prior(bump_->mapping->germs());
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

// The full 101 x 101 grid of SPEC §3.5, for timing reports only:
// run with --gtest_also_run_disabled_tests.
TEST(SpeedBumpPosteriorTiming, DISABLED_FullCoarseGrid) {
  const SpeedBumpCase c = makeSpeedBumpCase(2008);
  const ReferencePosterior r =
      computeReferencePosterior(*c.model, *c.mapping, c.series, c.noise, c.integration,
                                ReferencePosteriorSettings(), nullptr,
                                [](const std::string& m) { std::printf("  %s\n", m.c_str()); });
  std::printf("101x101: xi mean (%.6f, %.6f) std (%.3e, %.3e); %zu mode(s) of %d maxima; "
              "%ld simulations; coarse %.2f s, refine %.2f s, fine %.2f s, total %.2f s\n",
              r.xi_mean[0], r.xi_mean[1], r.xi_stddev[0], r.xi_stddev[1], r.modes.size(),
              r.coarse_local_maxima, r.simulations, r.coarse_seconds, r.refine_seconds,
              r.fine_seconds, r.total_seconds);
  EXPECT_LT(std::abs(r.xi_mean[0] - c.truth[0]), 4.0 * r.xi_stddev[0]);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
