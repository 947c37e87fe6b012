// Health checks (docs/method.md §5) and the forecast's handling of collocation
// points outside the model's domain (docs/method.md §4.1), on the paper's appendix
// model y' = a y to show the filters are model-agnostic.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>

#include "pc_ekf/filter/health.h"
#include "pc_ekf/pc/pc_statistics.h"
#include "pc_ekf/filter/one_step_filter.h"
#include "pc_ekf/model/scalar_growth_model.h"

namespace pc_ekf {
namespace {

TEST(Health, ChiSquareQuantilesMatchTables) {
  // Standard table values.
  EXPECT_NEAR(chiSquareQuantile(0.995, 1), 7.879438576622, 1e-8);
  EXPECT_NEAR(chiSquareQuantile(0.005, 1), 3.92704e-5, 1e-9);
  // dof 4 has the closed-form CDF 1 - exp(-x/2) (1 + x/2).
  for (double p : {0.005, 0.5, 0.995}) {
    const double x = chiSquareQuantile(p, 4);
    EXPECT_NEAR(1.0 - std::exp(-x / 2) * (1 + x / 2), p, 1e-12);
  }
  EXPECT_NEAR(chiSquareQuantile(0.995, 4), 14.860259, 1e-6);
  EXPECT_NEAR(chiSquareQuantile(0.5, 2), 2.0 * std::log(2.0), 1e-12);
}

TEST(Health, CoherenceDisagreementInCombinedStandardDeviations) {
  const Eigen::VectorXd d = coherenceDisagreement(Eigen::Vector2d(10.0, 1.0), Eigen::Vector2d(3.0, 0.1),
                                                  Eigen::Vector2d(14.0, 1.0), Eigen::Vector2d(4.0, 0.2));
  EXPECT_DOUBLE_EQ(d[0], 4.0 / 5.0);
  EXPECT_DOUBLE_EQ(d[1], 0.0);
}

struct GrowthProblem {
  std::shared_ptr<ScalarGrowthModel> model;
  std::shared_ptr<PcPropagator> propagator;
  explicit GrowthProblem(double range, GermFamily family = GermFamily::kUniform,
                         std::shared_ptr<ScalarGrowthModel> m = nullptr)
      : model(m ? m : std::make_shared<ScalarGrowthModel>(0.5, 1.0)) {
    std::vector<UncertainParameter> u{{"growth_rate", 0.5, range, GermSpec{family, 2.0, 2.0}}};
    ParameterMapping mapping(*model, u);
    const PolynomialBasis basis(mapping.germs(), 3);
    const CollocationDesign design(basis, PointSequence::kHalton, 8);
    propagator = std::make_shared<PcPropagator>(model, basis, design, mapping, IntegratorSettings{1e-3});
  }
};

// y' = a y with a physical domain a < limit (the growth model itself accepts
// any finite rate), so that some collocation points of the prior fall outside.
class BoundedGrowthModel : public ScalarGrowthModel {
 public:
  explicit BoundedGrowthModel(double limit) : ScalarGrowthModel(0.5, 1.0), limit_(limit) {}
  std::string invalidReason(const Eigen::Ref<const Eigen::VectorXd>& params) const override {
    const std::string base = ScalarGrowthModel::invalidReason(params);
    if (!base.empty()) return base;
    return params[0] < limit_ ? "" : "growth_rate " + std::to_string(params[0]) + " >= limit";
  }

 private:
  double limit_;
};

TEST(Health, GrowthModelEstimatesItsRateAndStaysCalibrated) {
  GrowthProblem p(0.5);
  OneStepSettings s;
  s.noise = NoiseModel{0.01, 1e-12};
  s.health.nis_window = 5;
  OneStepFilter f(p.propagator, s);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n;
  const double a = 0.6;  // truth
  StepResult r;
  int nis_outside = 0;
  for (int k = 1; k <= 20; ++k) {
    const double t = 0.1 * k, y = std::exp(a * t);
    r = f.process(Measurement{t, {0}, Eigen::VectorXd::Constant(1, y * (1 + 0.01 * n(rng)))});
    nis_outside += r.health.nis_outside;
    EXPECT_FALSE(r.health.non_finite);
  }
  EXPECT_NEAR(r.mean[0], a, 3 * r.stddev[0]);
  EXPECT_LT(r.stddev[0], 0.01);
  EXPECT_TRUE(r.health.healthy());
  EXPECT_LE(nis_outside, 2);
  EXPECT_NEAR(r.health.nis_lower, chiSquareQuantile(0.005, 1), 1e-12);
}

TEST(Health, InconsistentDataTripsTheWindowedNis) {
  GrowthProblem p(0.1);
  OneStepSettings s;
  s.noise = NoiseModel{0.001, 1e-12};
  s.health.nis_window = 5;
  OneStepFilter f(p.propagator, s);
  StepResult r;
  for (int k = 1; k <= 10; ++k) {
    const double t = 0.1 * k;  // data grow at rate 2, far outside the prior 0.5 +- 0.05
    r = f.process(Measurement{t, {0}, Eigen::VectorXd::Constant(1, std::exp(2.0 * t))});
  }
  EXPECT_TRUE(r.health.nis_window_outside);
  EXPECT_FALSE(r.health.healthy());
  EXPECT_FALSE(r.health.warnings().empty());
}

TEST(Health, MassOutsideThePriorSupportIsMeasured) {
  GrowthProblem p(0.5);
  HealthMonitor monitor(*p.propagator, HealthSettings{});
  // A uniform prior on [0.25, 0.75]; shift the mean to 0.75: half the mass outside.
  Eigen::MatrixXd c = p.propagator->priorState().bottomRows(1);
  const HealthStatus inside = monitor.assess(UpdateDiagnostics{}, ForecastReport{}, c);
  EXPECT_DOUBLE_EQ(inside.mass_outside_support[0], 0.0);
  c(0, 0) = 0.75;
  const HealthStatus shifted = monitor.assess(UpdateDiagnostics{}, ForecastReport{}, c);
  EXPECT_NEAR(shifted.mass_outside_support[0], 0.5, 0.03);
  EXPECT_TRUE(shifted.support_exceeded);
  EXPECT_FALSE(shifted.band_nested);  // the band moved outside the previous one
}

// support_every: 0 (estimate_offline's coherence filter): no mass per sample, and
// assessSupport on the last sample gives what assess gave there.
TEST(Health, SupportAssessedOnRequestEqualsThePerSampleOne) {
  GrowthProblem p(0.5);
  OneStepSettings every;
  every.noise = NoiseModel{0.01, 1e-12};
  OneStepSettings on_request = every;
  on_request.health.support_every = 0;
  OneStepFilter a(p.propagator, every), b(p.propagator, on_request);
  StepResult ra, rb;
  for (int k = 1; k <= 8; ++k) {
    // Data at rate 0.78: the posterior moves against the prior's upper bound 0.75.
    const Measurement m{0.1 * k, {0}, Eigen::VectorXd::Constant(1, std::exp(0.78 * 0.1 * k))};
    ra = a.process(m);
    rb = b.process(m);
    ASSERT_EQ(ra.health.mass_outside_support.size(), 1);
    EXPECT_EQ(rb.health.mass_outside_support.size(), 0) << k;
    EXPECT_FALSE(rb.health.support_exceeded);
    EXPECT_EQ(ra.mean, rb.mean) << k;  // nothing else depends on it
  }
  b.assessSupport(&rb);
  ASSERT_EQ(rb.health.mass_outside_support.size(), 1);
  EXPECT_GT(ra.health.mass_outside_support[0], 0.0);
  EXPECT_EQ(rb.health.mass_outside_support[0], ra.health.mass_outside_support[0]);
  EXPECT_EQ(rb.health.support_exceeded, ra.health.support_exceeded);
  // The support's rate judges assessed samples only: b assessed none in the run.
  EXPECT_EQ(ra.health.rates.support.run.trials, 8);
  EXPECT_EQ(rb.health.rates.support.run.trials, 0);
  HealthStatus same_rates = ra.health;
  same_rates.rates = rb.health.rates;
  EXPECT_EQ(rb.health.warnings(), same_rates.warnings());
}

// The mass outside the support skips the draws that its bounds show inside;
// the count must still be the full product's (psi * c over all draws), for
// expansions that straddle a bound by a little (a tolerance near its prior)
// and by much.
TEST(Health, MassOutsideCountsTheDrawsOfTheFullProduct) {
  GrowthProblem p(0.5);  // uniform rate on [0.25, 0.75], order 3 (S = 4)
  const HealthSettings settings;
  const PolynomialBasis& basis = p.propagator->basis();
  const Eigen::MatrixXd psi =
      basis.evaluate(sampleGerms(basis, settings.support_draws, settings.seed));
  const Eigen::MatrixXd prior = p.propagator->priorState().bottomRows(1);
  HealthMonitor monitor(*p.propagator, settings);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int straddling = 0, few = 0;
  for (int trial = 0; trial < 400; ++trial) {
    Eigen::MatrixXd c = prior;
    const double scale = trial % 2 ? 1e-3 : 0.1;  // near the prior, or far from it
    for (Eigen::Index j = 0; j < c.cols(); ++j) c(0, j) += scale * u(rng);
    const Eigen::VectorXd v = psi * c.row(0).transpose();
    int expected = 0;
    for (Eigen::Index d = 0; d < v.size(); ++d) expected += v[d] < 0.25 || v[d] > 0.75;
    const HealthStatus h = monitor.assess(UpdateDiagnostics{}, ForecastReport{}, c);
    ASSERT_EQ(h.mass_outside_support[0], expected / static_cast<double>(v.size())) << trial;
    straddling += expected > 0;
    few += expected > 0 && expected < 20;
  }
  EXPECT_GT(straddling, 100);  // the test exercises draws outside, a few and many
  EXPECT_GT(few, 20);
}

// gemvValue repeats the product's sums: equal bit for bit, with one block of
// terms (S < 128) and with several (S = 165).
TEST(Health, GemvValueEqualsTheMatrixVectorProduct) {
  for (int order : {2, 3}) {
    const PolynomialBasis basis(std::vector<GermSpec>(8, GermSpec{GermFamily::kBeta, 2.0, 2.0}), order);
    const Eigen::MatrixXd psi = basis.evaluate(sampleGerms(basis, 2000, 3));
    std::mt19937_64 rng(order);
    std::normal_distribution<double> n;
    Eigen::VectorXd c(basis.size());
    for (Eigen::Index j = 0; j < c.size(); ++j) c[j] = n(rng) / (1.0 + j);
    const Eigen::VectorXd v = psi * c;
    const int block_cols = gemvBlockColumns(psi.rows(), psi.cols());
    EXPECT_EQ(block_cols, basis.size() < 128 ? basis.size() : 16);
    for (Eigen::Index d = 0; d < psi.rows(); ++d) {
      ASSERT_EQ(gemvValue(psi.data() + d, psi.rows(), c.data(), c.size(), block_cols), v[d]);
    }
    // The lanes' version over blocks of 48 draws (rows padded by 16).
    Eigen::MatrixXd padded = Eigen::MatrixXd::Zero(psi.rows() + 16, psi.cols());
    padded.topRows(psi.rows()) = psi;
    std::vector<const double*> columns(psi.cols());
    std::vector<double> values(48);
    for (Eigen::Index d0 = 0; d0 < psi.rows(); d0 += 48) {
      const int count = static_cast<int>(std::min<Eigen::Index>(48, psi.rows() - d0));
      for (Eigen::Index j = 0; j < psi.cols(); ++j) columns[j] = padded.col(j).data() + d0;
      gemvOrderValues(columns.data(), c.data(), static_cast<int>(c.size()), block_cols, count,
                      values.data());
      for (int b = 0; b < count; ++b) ASSERT_EQ(values[b], v[d0 + b]);
    }
  }
}

TEST(Health, PointsOutsideTheDomainAreReportedNotFatal) {
  // Uniform a in [0.25, 0.75] (the state of an unbounded model), forecast by
  // a model whose domain is a < 0.6, as when the parameters drifted out of
  // it: the points beyond are dropped, the projection is least squares on the rest.
  const double limit = 0.6, dt = 0.1;
  const Eigen::MatrixXd prior = GrowthProblem(0.5).propagator->priorState();  // [y; a] x S
  GrowthProblem p(0.5, GermFamily::kUniform, std::make_shared<BoundedGrowthModel>(limit));
  const CollocationDesign& design = p.propagator->design();
  const Eigen::MatrixXd rates = p.propagator->mapping().valuesAtGerms(design.points());  // 1 x Q
  const Eigen::MatrixXd y0 = design.evaluateAtPoints(prior.topRows(1));                  // 1 x Q
  std::vector<Eigen::Index> kept;
  for (Eigen::Index q = 0; q < rates.cols(); ++q) {
    if (rates(0, q) < limit) kept.push_back(q);
  }
  const int outside = static_cast<int>(rates.cols()) - static_cast<int>(kept.size());
  ASSERT_GT(outside, 0);  // the test needs points on both sides of the limit
  ASSERT_GE(kept.size(), static_cast<std::size_t>(p.propagator->termCount()));

  Eigen::MatrixXd x = prior;
  const ForecastReport r = p.propagator->forecast(x, 0.0, dt);
  EXPECT_EQ(r.invalid_points, outside);
  EXPECT_EQ(r.nonfinite_points, 0);
  EXPECT_TRUE(r.ok) << r.first_problem;
  EXPECT_NE(r.first_problem.find(">= limit"), std::string::npos) << r.first_problem;
  // Independent projection: exact y0 e^{a dt} at the kept points, least squares.
  Eigen::MatrixXd a(kept.size(), design.designMatrix().cols());
  Eigen::VectorXd v(kept.size());
  for (std::size_t i = 0; i < kept.size(); ++i) {
    a.row(i) = design.designMatrix().row(kept[i]);
    v(i) = y0(0, kept[i]) * std::exp(rates(0, kept[i]) * dt);
  }
  const Eigen::VectorXd expected = a.colPivHouseholderQr().solve(v);
  for (Eigen::Index j = 0; j < expected.size(); ++j) {
    EXPECT_NEAR(x(0, j), expected(j), 1e-12) << "state coefficient " << j;
  }

  // With fewer admissible points than basis terms the forecast fails, named.
  const double tight = 0.4;
  int admissible = 0;
  for (Eigen::Index q = 0; q < rates.cols(); ++q) admissible += rates(0, q) < tight;
  ASSERT_LT(admissible, p.propagator->termCount());
  GrowthProblem few(0.5, GermFamily::kUniform, std::make_shared<BoundedGrowthModel>(tight));
  Eigen::MatrixXd xf = prior;
  const ForecastReport f = few.propagator->forecast(xf, 0.0, dt);
  EXPECT_EQ(f.invalid_points, static_cast<int>(rates.cols()) - admissible);
  EXPECT_FALSE(f.ok);
}

TEST(Health, MeasurementsBeforeTheFilterTimeAreRejectedWithoutDamage) {
  GrowthProblem p(0.5);
  OneStepFilter f(p.propagator, OneStepSettings{});
  f.process(Measurement{0.2, {0}, Eigen::VectorXd::Constant(1, 1.1)});
  const Eigen::MatrixXd before = f.state();
  EXPECT_THROW(f.process(Measurement{0.1, {0}, Eigen::VectorXd::Constant(1, 1.0)}),
               std::invalid_argument);
  EXPECT_THROW(f.process(Measurement{0.3, {1}, Eigen::VectorXd::Constant(1, 1.0)}),
               std::invalid_argument);
  EXPECT_THROW(f.process(Measurement{0.3, {0}, Eigen::VectorXd::Constant(1, NAN)}),
               std::invalid_argument);
  EXPECT_EQ(f.state(), before);
  EXPECT_EQ(f.samples(), 1);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
