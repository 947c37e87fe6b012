// The paper's speed-bump cases (docs/method.md §6) judged against the exact posterior
// (docs/method.md §4.6) and over many noise seeds. Seeds are fixed, not selected.
#include <gtest/gtest.h>

#include <cmath>

#include "pc_ekf/filter/one_step_filter.h"
#include "pc_ekf/reference/reference_posterior.h"
#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/io/offline_estimation.h"

namespace pc_ekf {
namespace {

const std::string kConfig = std::string(PC_EKF_SOURCE_DIR) + "/config/speed_bump.yaml";

// The settings a real vehicle starts from (its schedule, its re-linearisation).
EstimatorConfig liveConfig() {
  return loadConfigFile(std::string(PC_EKF_SOURCE_DIR) + "/config/vehicle_live.yaml");
}

struct CaseData {
  EstimatorConfig config;
  std::shared_ptr<const MechanicalModel> model;
  MeasurementSeries data;
};

CaseData makeRun(int samples, std::uint64_t seed) {
  CaseData r;
  r.config = loadConfigFile(kConfig);
  r.config.sampling.samples = samples;
  r.model = makeModel(r.config, makeRoad(r.config));
  r.data = synthesizeFromConfig(r.config, *r.model, seed);
  return r;
}

OfflineResult estimate(const CaseData& r, EstimationMethod m, UpdateRule rule, std::uint64_t seed = 1) {
  EstimatorConfig c = r.config;
  c.update = rule;
  return runOfflineEstimation(c, r.data, r.model, m, seed);
}

TEST(PaperCaseA, SquareRootOneStepAndEsMdaAgainstTheReferencePosterior) {
  const CaseData run = makeRun(10, 1);
  const OfflineResult grid = estimate(run, EstimationMethod::kGrid, UpdateRule::kSquareRoot);
  ASSERT_EQ(grid.modes, 1);
  EXPECT_LT(grid.border_mass, 1e-6);
  const OfflineResult one = estimate(run, EstimationMethod::kOneStep, UpdateRule::kSquareRoot);
  const OfflineResult esmda = estimate(run, EstimationMethod::kEsMda, UpdateRule::kSquareRoot);
  for (int i = 0; i < 2; ++i) {
    const double post_mean = grid.parameters[i].mean, post_std = grid.parameters[i].stddev;
    const ParameterSummary& o = one.parameters[i];
    EXPECT_LT(std::abs(o.mean - post_mean), 2.0 * o.stddev) << o.name;
    EXPECT_GT(o.stddev, 0.7 * post_std) << o.name;
    EXPECT_LT(o.stddev, 10.0 * post_std) << o.name;
    const ParameterSummary& e = esmda.parameters[i];
    EXPECT_LT(std::abs(e.mean - post_mean), 1.5 * post_std) << e.name;
    EXPECT_GT(e.stddev, 0.7 * post_std) << e.name;
    EXPECT_LT(e.stddev, 2.0 * post_std) << e.name;
    RecordProperty(o.name + "_posterior", std::to_string(post_mean) + " +- " + std::to_string(post_std));
  }
}

// ES-MDA's first passes linearise over the whole prior; with equal weights
// ([4, 4, 4, 4]) that error stays in the result, a bias of about 1.4 exact
// posterior std on the bump at N = 100 (the same sign every seed). The
// decreasing schedule of vehicle_live.yaml weights the well-linearised last
// pass most and lands on the exact posterior.
TEST(PaperCaseB, DecreasingInflationScheduleRemovesEsMdaBias) {
  const std::vector<double> live = liveConfig().es_mda.alphas;
  ASSERT_GT(live.size(), 4u);
  for (std::uint64_t seed : {1, 2}) {
    CaseData run = makeRun(100, seed);
    const OfflineResult grid = estimate(run, EstimationMethod::kGrid, UpdateRule::kSquareRoot);
    const OfflineResult equal = estimate(run, EstimationMethod::kEsMda, UpdateRule::kSquareRoot);
    run.config.es_mda.alphas = live;
    const OfflineResult decreasing = estimate(run, EstimationMethod::kEsMda, UpdateRule::kSquareRoot);
    for (int i = 0; i < 2; ++i) {
      const double post_mean = grid.parameters[i].mean, post_std = grid.parameters[i].stddev;
      const ParameterSummary& d = decreasing.parameters[i];
      EXPECT_LT(std::abs(d.mean - post_mean), 0.3 * post_std) << d.name << " seed " << seed;
      EXPECT_NEAR(d.stddev, post_std, 0.1 * post_std) << d.name;
      EXPECT_GT(std::abs(equal.parameters[i].mean - post_mean), 0.8 * post_std) << d.name;
    }
  }
}

// The one-step filter's first updates linearise over the whole prior; that
// error stays (measured: 1-3.6 exact-posterior std from the exact posterior
// mean on the bump at N = 100, its sign changing with the noise draw).
// Re-linearisation (vehicle_live.yaml's filter.relinearize) re-runs the kept
// samples from a working prior around the estimate and lands on the exact
// posterior.
TEST(PaperCaseB, RelinearizationPutsTheOneStepFilterOnTheExactPosterior) {
  const RelinearizeSettings live = liveConfig().safeguards.relinearize;
  ASSERT_GT(live.shrink, 0.0);
  double plain_worst = 0.0;
  for (std::uint64_t seed : {1, 2}) {
    CaseData run = makeRun(100, seed);
    const OfflineResult grid = estimate(run, EstimationMethod::kGrid, UpdateRule::kSquareRoot);
    const OfflineResult plain = estimate(run, EstimationMethod::kOneStep, UpdateRule::kSquareRoot);
    run.config.safeguards.relinearize = live;
    const OfflineResult relin = estimate(run, EstimationMethod::kOneStep, UpdateRule::kSquareRoot);
    EXPECT_GE(relin.relinearized, 1);
    EXPECT_TRUE(relin.healthy);
    for (int i = 0; i < 2; ++i) {
      const double post_mean = grid.parameters[i].mean, post_std = grid.parameters[i].stddev;
      const ParameterSummary& r = relin.parameters[i];
      EXPECT_LT(std::abs(r.mean - post_mean), 0.1 * post_std) << r.name << " seed " << seed;
      EXPECT_NEAR(r.stddev, post_std, 0.03 * post_std) << r.name << " seed " << seed;
      plain_worst = std::max(plain_worst, std::abs(plain.parameters[i].mean - post_mean) / post_std);
    }
  }
  EXPECT_GT(plain_worst, 1.0);
}

// Re-linearisation needs every sample since the start: a restored state ends
// it (the filter then runs exactly as without it), reset() starts it afresh.
TEST(PaperCaseB, RelinearizationEndsOnRestoreAndStartsAgainOnReset) {
  CaseData run = makeRun(100, 1);
  run.config.safeguards.relinearize = liveConfig().safeguards.relinearize;
  const auto prop = makePropagator(run.config, run.model);
  EstimatorConfig plain_config = run.config;
  plain_config.safeguards.relinearize.shrink = 0.0;
  OneStepFilter plain(prop, makeOneStepSettings(plain_config));
  OneStepFilter fresh(prop, makeOneStepSettings(run.config));
  OneStepFilter restored(prop, makeOneStepSettings(run.config));
  StepResult p, f, r;
  for (std::size_t k = 0; k < run.data.size(); ++k) {
    p = plain.process(run.data[k]);
    f = fresh.process(run.data[k]);
    if (k == 5) restored.restore(restored.state(), restored.time(), restored.samples());
    r = restored.process(run.data[k]);
  }
  EXPECT_GE(f.restarts, 1);
  EXPECT_EQ(r.restarts, 0);
  EXPECT_EQ(r.mean, p.mean);  // bit for bit: no restart came before sample 6
  EXPECT_NE(f.mean, p.mean);
  // The working prior travels with a restored state (a checkpoint's
  // full.working): the restored filter reports what the live one did; without
  // it, the filter's own (uncorrected) state.
  ASSERT_TRUE(run.config.safeguards.relinearize.prior_correction);
  ASSERT_GT(fresh.workingPrior().size(), 0);
  OneStepFilter resumed(prop, makeOneStepSettings(run.config));
  resumed.restore(fresh.state(), fresh.time(), fresh.samples(), fresh.workingPrior());
  StepResult reported;
  reported.coefficients = resumed.state().bottomRows(prop->parameterCount());
  resumed.report(reported);
  EXPECT_EQ(reported.mean, f.mean);
  EXPECT_EQ(reported.stddev, f.stddev);
  resumed.restore(fresh.state(), fresh.time(), fresh.samples());
  StepResult own;
  own.coefficients = resumed.state().bottomRows(prop->parameterCount());
  resumed.report(own);
  EXPECT_EQ(own.coefficients, fresh.state().bottomRows(prop->parameterCount()));
  EXPECT_NE(own.coefficients, f.coefficients);
  fresh.reset();
  StepResult again;
  for (const Measurement& m : run.data) again = fresh.process(m);
  EXPECT_EQ(again.restarts, f.restarts);
  EXPECT_EQ(again.mean, f.mean);
  EXPECT_EQ(again.stddev, f.stddev);
}

// Both approximate the same linear-update estimator (docs/method.md §4.6 note). The
// square-root ensemble (same serial rule as the PC-EKF) isolates what the
// observation perturbations add: measured on this case, the perturbed EnKF's
// d_CG sits 0.27-0.33 of its std from the PC-EKF for every ensemble seed
// (spread 0.02 std), the square-root ensemble within 0.1.
TEST(PaperCaseA, LargeEnkfApproximatesTheSameLinearUpdateEstimator) {
  CaseData run = makeRun(10, 1);
  run.config.enkf.members = 2000;
  const OfflineResult pc = estimate(run, EstimationMethod::kOneStep, UpdateRule::kSquareRoot);
  const OfflineResult enkf = estimate(run, EstimationMethod::kEnkf, UpdateRule::kSquareRoot);
  run.config.enkf.square_root = true;
  const OfflineResult eakf = estimate(run, EstimationMethod::kEnkf, UpdateRule::kSquareRoot);
  for (int i = 0; i < 2; ++i) {
    const ParameterSummary& e = enkf.parameters[i];
    const ParameterSummary& s = eakf.parameters[i];
    EXPECT_LT(std::abs(s.mean - pc.parameters[i].mean), 0.3 * s.stddev) << s.name;
    EXPECT_LT(std::abs(e.mean - pc.parameters[i].mean), 0.4 * e.stddev) << e.name;
    EXPECT_NEAR(e.stddev / pc.parameters[i].stddev, 1.0, 0.15) << e.name;
    EXPECT_NEAR(s.stddev / pc.parameters[i].stddev, 1.0, 0.15) << s.name;
    std::printf("%s: pc %.6g +- %.3g, enkf %.6g +- %.3g (%.2f std), eakf %.6g +- %.3g (%.2f std)\n",
                e.name.c_str(), pc.parameters[i].mean, pc.parameters[i].stddev, e.mean, e.stddev,
                std::abs(e.mean - pc.parameters[i].mean) / e.stddev, s.mean, s.stddev,
                std::abs(s.mean - pc.parameters[i].mean) / s.stddev);
  }
}

// Smallest k with P(X < k) <= alpha for X ~ Binomial(n, p).
int binomialLowerBound(int n, double p, double alpha) {
  double below = 0.0;  // P(X < k)
  for (int k = 0; k <= n; ++k) {
    const double pk =
        std::exp(std::lgamma(n + 1.0) - std::lgamma(k + 1.0) - std::lgamma(n - k + 1.0) +
                 k * std::log(p) + (n - k) * std::log1p(-p));
    if (below + pk > alpha) return k;
    below += pk;
  }
  return n;
}

TEST(PaperCaseB, SquareRootCoversTheTruthAndStaysCoherentWhereThePaperRuleDoesNot) {
  const int seeds = 30;
  const EstimatorConfig base = loadConfigFile(kConfig);
  const Eigen::VectorXd truth = base.parameterValues(
      Eigen::Map<const Eigen::VectorXd>(base.truth.xi.data(), base.truth.xi.size()));
  int covered[2][2] = {{0, 0}, {0, 0}};  // [rule][parameter]
  int flagged[2] = {0, 0};
  const UpdateRule rules[2] = {UpdateRule::kSquareRoot, UpdateRule::kPaper};
  for (int s = 1; s <= seeds; ++s) {
    const CaseData run = makeRun(100, s);
    for (int u = 0; u < 2; ++u) {
      const OfflineResult r = estimate(run, EstimationMethod::kOneStep, rules[u]);
      ASSERT_TRUE(r.coherence.available);
      for (int i = 0; i < 2; ++i) {
        covered[u][i] += std::abs(r.parameters[i].mean - truth[i]) <= 2.0 * r.parameters[i].stddev;
      }
      flagged[u] += r.coherence.flagged;
    }
  }
  const double sqrt_m = covered[0][0] / double(seeds), sqrt_d = covered[0][1] / double(seeds);
  const double paper_m = covered[1][0] / double(seeds), paper_d = covered[1][1] / double(seeds);
  // A calibrated Gaussian estimate covers the truth with +-2 std in
  // erf(sqrt 2) = 95.45 % of runs, so the covered count of 30 independent
  // seeds is Binomial(30, 0.9545). The bound is the count below which a
  // calibrated filter falls with probability at most 1e-3: 24 (P(X <= 23) =
  // 3.3e-4, P(X <= 24) = 2.0e-3). Measured on these seeds: 27 and 27.
  const int min_covered = binomialLowerBound(seeds, std::erf(2.0 / std::sqrt(2.0)), 1e-3);
  EXPECT_EQ(min_covered, 24);
  EXPECT_GE(covered[0][0], min_covered) << "M coverage " << sqrt_m;
  EXPECT_GE(covered[0][1], min_covered) << "d_CG coverage " << sqrt_d;
  EXPECT_GT(covered[0][0] + covered[0][1], covered[1][0] + covered[1][1]);
  EXPECT_GE(flagged[1], 0.2 * seeds);
  EXPECT_LE(flagged[0], 0.05 * seeds);
  std::printf("case B coverage: square_root %.2f/%.2f, paper %.2f/%.2f; coherence flags %d vs %d of %d\n",
              sqrt_m, sqrt_d, paper_m, paper_d, flagged[0], flagged[1], seeds);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
