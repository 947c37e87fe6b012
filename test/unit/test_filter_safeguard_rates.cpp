// The safeguards' own rates as health checks (docs/method.md §5.9, issue 33):
// the binomial and Poisson tails in closed form, the monitor's window and run
// counts, and the one-step filter on data the model cannot explain (20 % of
// the samples from another vehicle: flagged through the gate's rate), on one
// real load change (not flagged) and on exact-model controls (50 seeds).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

#include "pc_ekf/filter/reopen_chance.h"
#include "pc_ekf/filter/safeguard_rates.h"
#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/io/offline_estimation.h"
#include "pc_ekf/model/roll_plane_model.h"

namespace pc_ekf {
namespace {

TEST(SafeguardRateTails, BinomialInClosedForm) {
  // P(X >= 1) = 1 - (1 - p)^n.
  EXPECT_NEAR(binomialUpperTail(1, 20, 1e-6), -std::expm1(20.0 * std::log1p(-1e-6)), 1e-18);
  // P(X >= 2), n = 10, p = 0.01: 1 - 0.99^10 - 10 * 0.01 * 0.99^9 = 0.0042662.
  const double two = 1.0 - std::pow(0.99, 10) - 0.1 * std::pow(0.99, 9);
  EXPECT_NEAR(binomialUpperTail(2, 10, 0.01), two, 1e-15);
  EXPECT_NEAR(two, 0.0042662, 1e-7);
  // Symmetric: P(X >= 50), n = 100, p = 1/2 = 1/2 + C(100, 50) / 2^101.
  const double c = std::exp(std::lgamma(101.0) - 2.0 * std::lgamma(51.0) - 100.0 * std::log(2.0));
  EXPECT_NEAR(binomialUpperTail(50, 100, 0.5), 0.5 + 0.5 * c, 1e-12);
  EXPECT_NEAR(binomialUpperTail(50, 100, 0.5), 0.5397946, 1e-7);
  // Below the mean (summed downwards): n = 1000, p = 0.01, P(X >= 3) = 1 - sum_{i<3}.
  double lower = 0.0;
  for (int i = 0; i < 3; ++i) {
    lower += std::exp(std::lgamma(1001.0) - std::lgamma(i + 1.0) - std::lgamma(1001.0 - i) +
                      i * std::log(0.01) + (1000 - i) * std::log(0.99));
  }
  EXPECT_NEAR(binomialUpperTail(3, 1000, 0.01), 1.0 - lower, 1e-13);
  EXPECT_DOUBLE_EQ(binomialUpperTail(0, 5, 0.1), 1.0);
  EXPECT_DOUBLE_EQ(binomialUpperTail(1, 5, 0.0), 0.0);  // an event that cannot happen
  EXPECT_DOUBLE_EQ(binomialUpperTail(6, 5, 0.5), 0.0);
}

TEST(SafeguardRateTails, PoissonInClosedForm) {
  EXPECT_NEAR(poissonUpperTail(1, 0.3), -std::expm1(-0.3), 1e-16);
  EXPECT_NEAR(poissonUpperTail(2, 0.5), 1.0 - std::exp(-0.5) * 1.5, 1e-16);
  // One load change a minute over 10 s: two re-opens are within the 99 %
  // bound (P = 0.0124), three are not (P = 6.8e-4).
  const double mu = 10.0 / 60.0;
  EXPECT_NEAR(poissonUpperTail(2, mu), 0.012437, 1e-6);
  EXPECT_NEAR(poissonUpperTail(3, mu), 1.0 - std::exp(-mu) * (1.0 + mu + mu * mu / 2.0), 1e-15);
  EXPECT_NEAR(poissonUpperTail(3, mu), 6.8e-4, 1e-5);
  // Far above the mean and below it.
  // Far above: pmf(30) (1 + mu/31 + mu^2/(31 32) + mu^3/(31 32 33) + ...), the rest below 1e-9 of it.
  const double pmf30 = std::exp(-0.17 + 30 * std::log(0.17) - std::lgamma(31.0)), m = 0.17;
  EXPECT_NEAR(poissonUpperTail(30, m),
              pmf30 * (1.0 + m / 31 + m * m / (31 * 32) + m * m * m / (31 * 32 * 33)), 1e-9 * pmf30);
  EXPECT_NEAR(poissonUpperTail(5, 10.0), 0.970747, 1e-6);
}

RateSettings rates(double gate) {
  RateSettings s;
  s.confidence = 0.99;
  s.window = 1.0;
  s.gate_probability = gate;
  s.damp_fraction = s.support_fraction = 0.01;
  s.reopen_rate = 1.0 / 60.0;
  return s;
}

TEST(SafeguardRateMonitor, DampedUpdatesAgainstTheirBinomialBound) {
  // Ten samples 0.1 s apart (all in the 1 s window): one damped update is
  // within the bound (P(X >= 1) = 0.096), two are not (P = 0.0043).
  SafeguardRateMonitor m(rates(0.0));
  m.reset(0.0);
  SafeguardRates r;
  for (int i = 1; i <= 10; ++i) r = m.add(0.1 * i, false, i == 3, false, 0);
  EXPECT_EQ(r.damped.window.count, 1);
  EXPECT_EQ(r.damped.window.trials, 10);
  EXPECT_NEAR(r.damped.window.expected, 0.1, 1e-15);
  EXPECT_FALSE(r.flagged());
  m.reset(0.0);
  for (int i = 1; i <= 10; ++i) r = m.add(0.1 * i, false, i == 3 || i == 7, false, 0);
  EXPECT_NEAR(r.damped.run.tail, 1.0 - std::pow(0.99, 10) - 0.1 * std::pow(0.99, 9), 1e-15);
  EXPECT_TRUE(r.damped.window.flagged);
  EXPECT_TRUE(r.damped.run.flagged);
  EXPECT_TRUE(r.flagged());
  EXPECT_EQ(r.warnings().size(), 1u);
  // Ninety clean samples later the window has forgotten them; the run (2 of 100,
  // P = 0.26) no longer flags either.
  for (int i = 11; i <= 100; ++i) r = m.add(0.1 * i, false, false, false, 0);
  EXPECT_EQ(r.damped.window.count, 0);
  EXPECT_EQ(r.damped.window.trials, 10);  // (9, 10] s
  EXPECT_EQ(r.damped.run.count, 2);
  EXPECT_FALSE(r.flagged());
}

TEST(SafeguardRateMonitor, TheSupportRateIsAWarningOnly) {
  // Three of ten samples with mass outside the support (allowance 1 %): the
  // rate is flagged and warned about, health is not (docs/method.md §5.9).
  SafeguardRateMonitor m(rates(0.0));
  m.reset(0.0);
  SafeguardRates r;
  for (int i = 1; i <= 10; ++i) r = m.add(0.1 * i, false, false, false, i <= 3 ? 1 : 0);
  EXPECT_EQ(r.support.run.count, 3);
  EXPECT_TRUE(r.support.flagged());
  EXPECT_FALSE(r.flagged());
  ASSERT_EQ(r.warnings().size(), 1u);
  EXPECT_NE(r.warnings()[0].find("warning only"), std::string::npos);
}

TEST(SafeguardRateMonitor, OneGatedSampleIsBeyondAOneInAMillionGate) {
  SafeguardRateMonitor m(rates(1e-6));
  m.reset(0.0);
  SafeguardRates r;
  for (int i = 1; i <= 20; ++i) r = m.add(0.01 * i, false, false, false, -1);
  EXPECT_FALSE(r.flagged());
  EXPECT_EQ(r.support.run.trials, 0);  // never assessed: never judged
  r = m.add(0.21, true, false, false, -1);
  EXPECT_TRUE(r.gated.window.flagged);
  EXPECT_TRUE(r.gated.run.flagged);
  EXPECT_NEAR(r.gated.run.tail, -std::expm1(21.0 * std::log1p(-1e-6)), 1e-18);
}

TEST(SafeguardRateMonitor, ReopensAgainstTheLoadChangeRate) {
  // Window 10 s, one load change a minute (samples every 0.01 s).
  RateSettings s = rates(0.0);
  s.window = 10.0;
  SafeguardRateMonitor m(s);
  // Two re-opens in the first 6 s of a run: exposure 6 s, P(X >= 2) = 0.0047: flagged.
  m.reset(0.0);
  SafeguardRates r;
  for (int i = 1; i <= 600; ++i) r = m.add(0.01 * i, false, false, i == 300 || i == 600, 0);
  EXPECT_NEAR(r.reopened.window.exposure, 6.0, 1e-12);
  EXPECT_NEAR(r.reopened.run.tail, 1.0 - std::exp(-0.1) * 1.1, 1e-15);
  EXPECT_TRUE(r.reopened.window.flagged);
  EXPECT_TRUE(r.reopened.run.flagged);
  // Two within a full 10 s window, 20 s into the run: P = 0.0124 (window),
  // 0.045 (run): within the bounds; a third within the window is not (6.8e-4).
  m.reset(0.0);
  for (int i = 1; i <= 1900; ++i) r = m.add(0.01 * i, false, false, i == 1200 || i == 1900, 0);
  EXPECT_NEAR(r.reopened.window.exposure, 10.0, 1e-12);
  EXPECT_EQ(r.reopened.window.count, 2);
  EXPECT_NEAR(r.reopened.window.tail, 0.012437, 1e-6);
  EXPECT_FALSE(r.flagged());
  r = m.add(19.5, false, false, true, 0);
  EXPECT_TRUE(r.reopened.window.flagged);
  EXPECT_NEAR(r.reopened.window.tail, 6.8e-4, 1e-5);
  // A re-open every quarter second (the real stream): flagged at the
  // first (P = 1 - exp(-0.25 / 60) = 0.0042 over the run's 0.25 s).
  m.reset(0.0);
  int first_flag = 0;
  for (int i = 1; i <= 400 && !first_flag; ++i) {
    r = m.add(0.01 * i, false, false, i % 25 == 0, 0);
    if (r.flagged()) first_flag = i;
  }
  EXPECT_EQ(first_flag, 25);
}

TEST(ChanceReopens, TheRuleInClosedFormForAOneSampleWindow) {
  // Window 1: each sample is judged alone, above the upper bound with
  // q = (1 - confidence) / 2. after 1: a re-open at every such sample, rate q.
  // after 2: two in a row (the window cleared after each re-open), a renewal
  // process with mean waiting time (1 + q) / q^2. Monte Carlo error of
  // 200 000 samples.
  EXPECT_NEAR(chanceReopenPerSample(1, 3, 0.99, 1), 0.005, 4.0 * std::sqrt(0.005 / 2e5));
  EXPECT_NEAR(chanceReopenPerSample(1, 2, 0.6, 1), 0.2, 4.0 * std::sqrt(0.2 * 0.8 / 2e5));
  // The chi-square draw's three forms (1, 2, more degrees of freedom).
  for (const int dof : {1, 2, 3, 5, 9, 40}) {
    EXPECT_NEAR(chanceReopenPerSample(1, dof, 0.9, 1), 0.05, 4.0 * std::sqrt(0.05 * 0.95 / 2e5))
        << dof << " dof";
  }
  const double q = 0.2, rate = q * q / (1.0 + q);
  EXPECT_NEAR(chanceReopenPerSample(1, 2, 0.6, 2), rate, 4.0 * std::sqrt(rate / 2e5));
  // A 20-sample window at 99 %: about 0.5 % of the samples are above, in runs,
  // so a re-open after 3 comes about once per 1000 samples; more rarely after 10.
  const double w3 = chanceReopenPerSample(20, 3, 0.99, 3);
  const double w10 = chanceReopenPerSample(20, 3, 0.99, 10);
  std::printf("chance re-opens per sample: window 20, 3 dof, after 3: %g; after 10: %g\n", w3, w10);
  EXPECT_GT(w3, 2e-4);
  EXPECT_LT(w3, 5e-3 / 3.0);
  EXPECT_LT(w10, w3);
  EXPECT_THROW(chanceReopenPerSample(0, 3, 0.99, 3), std::invalid_argument);
}

TEST(ChanceReopens, TheShippedRulesTableHoldsTheSimulationsValues) {
  // Window 20, 99 %, after 20 (every shipped config with re-opens): the
  // values come from a table, each the seeded simulation's own (its counts
  // are 0 to 5 of 200 000 samples, so anything but the same value is a
  // stale or wrong entry).
  for (int dof = 1; dof <= 24; ++dof) {
    EXPECT_EQ(chanceReopenPerSample(20, dof, 0.99, 20), simulateChanceReopenPerSample(20, dof, 0.99, 20))
        << dof << " dof";
  }
  // Beyond the table, and any other rule, simulated as before.
  EXPECT_EQ(chanceReopenPerSample(20, 25, 0.99, 20), simulateChanceReopenPerSample(20, 25, 0.99, 20));
  EXPECT_EQ(chanceReopenPerSample(20, 4, 0.99, 19), simulateChanceReopenPerSample(20, 4, 0.99, 19));
  EXPECT_THROW(simulateChanceReopenPerSample(20, 0, 0.99, 20), std::invalid_argument);
}

TEST(SafeguardRateMonitor, ChanceReopensAreExpectedBesideLoadChanges) {
  // 10 s at 200 Hz, three re-opens. Load changes alone (1 per 60 s) expect
  // 0.167: flagged (P = 6.8e-4). With the rule's chance rate of 1.5e-3 per
  // sample the model expects 3.17: P(X >= 3) = 0.61, not flagged.
  RateSettings s = rates(0.0);
  SafeguardRateMonitor m(s);
  SafeguardRates without, with;
  m.reset(0.0);
  for (int i = 1; i <= 2000; ++i) without = m.add(0.005 * i, false, false, i % 600 == 0, 0);
  m.reset(0.0);
  for (int i = 1; i <= 2000; ++i) with = m.add(0.005 * i, false, false, i % 600 == 0, 0, 1.5e-3);
  EXPECT_EQ(without.reopened.run.count, 3);
  EXPECT_TRUE(without.reopened.run.flagged);
  EXPECT_NEAR(with.reopened.run.expected, 10.0 / 60.0 + 3.0, 1e-9);
  // The 1 s window: its own 200 samples' chance.
  EXPECT_NEAR(with.reopened.window.expected, 1.0 / 60.0 + 1.5e-3 * 200, 1e-9);
  const double mu = 10.0 / 60.0 + 3.0;
  EXPECT_NEAR(with.reopened.run.tail, 1.0 - std::exp(-mu) * (1.0 + mu + mu * mu / 2.0), 1e-12);
  EXPECT_FALSE(with.flagged());
}

// ---- the one-step filter ----

// The speed bump with the live configs' safeguards (vehicle_live.yaml: gate
// 1e-6, damping, drift on M, window 20) and the re-open rule at its quickest,
// after 3 (the configs wait 20 samples: at their rates of 200 Hz to 1 kHz
// after 3 re-opened by chance about once per 1000 samples).
EstimatorConfig liveBump(int samples) {
  EstimatorConfig c = loadConfigFile(std::string(PC_EKF_SOURCE_DIR) + "/config/speed_bump.yaml");
  c.sampling.samples = samples;
  c.health.nis_window = 20;
  c.health.innovation_gate = 1e-6;
  c.safeguards.support = SupportRule::kDamp;
  c.safeguards.drift = Eigen::Vector2d(2.0, 0.0);
  c.safeguards.reopen = {ReopenMode::kWidth, 0.5, 3};
  return c;
}

// Data of another vehicle (softer springs, weaker dampers, a lighter body) on the same road.
MeasurementSeries otherVehicle(const EstimatorConfig& c, std::uint64_t seed) {
  EstimatorConfig truth = c;
  VehicleParameters v = VehicleParameters::from(*c.model);
  for (double& k : v.spring_linear) k *= 0.7;
  for (double& d : v.damping) d *= 0.6;
  v.bar_mass *= 0.8;
  truth.model = std::make_shared<ModelParameters>(v.toModelParameters());
  return synthesizeFromConfig(truth, *makeModel(truth, makeRoad(truth)), seed);
}

TEST(SafeguardRateFilter, TwentyPercentOfAnotherVehicleIsFlaggedByTheGateRate) {
  const EstimatorConfig c = liveBump(100);
  const auto model = makeModel(c, makeRoad(c));
  const MeasurementSeries own = synthesizeFromConfig(c, *model, 1);
  const MeasurementSeries other = otherVehicle(c, 2);
  // Control: the own vehicle alone.
  const OfflineResult clean = runOfflineEstimation(c, own, model, EstimationMethod::kOneStep, 1);
  EXPECT_EQ(clean.rejected_samples, 0);
  EXPECT_FALSE(clean.safeguard_rates.flagged());
  EXPECT_TRUE(clean.healthy);
  // Every fifth sample (20 %) read from the other vehicle.
  MeasurementSeries spliced = own;
  for (std::size_t k = 4; k < spliced.size(); k += 5) spliced[k] = other[k];
  const OfflineResult r = runOfflineEstimation(c, spliced, model, EstimationMethod::kOneStep, 1);
  std::printf("20 %% foreign: healthy %d, gated %d of %d, damped %d, re-opens %d, gate P(run) %g\n",
              r.healthy, r.rejected_samples, r.samples, r.damped_updates, r.reopened,
              r.safeguard_rates.gated.run.tail);
  EXPECT_FALSE(r.healthy);
  EXPECT_GT(r.rejected_samples, 0);
  const SafeguardRate& g = r.safeguard_rates.gated;
  EXPECT_EQ(g.run.count, r.rejected_samples);
  EXPECT_EQ(g.run.trials, 100);
  EXPECT_TRUE(g.run.flagged);
  EXPECT_LT(g.run.tail, 1e-3);
  bool named = false;
  for (const auto& w : r.warnings) named = named || w.find("innovation gate rate") != std::string::npos;
  EXPECT_TRUE(named);
}

// config/load_change_course.yaml (M +40 kg at t = 6 s) with the live safeguards.
TEST(SafeguardRateFilter, OneLoadChangeIsNotFlagged) {
  EstimatorConfig c =
      loadConfigFile(std::string(PC_EKF_SOURCE_DIR) + "/config/load_change_course.yaml");
  c.health.nis_window = 20;
  c.health.innovation_gate = 1e-6;
  c.safeguards.drift = Eigen::Vector2d(2.0, 0.0);
  c.safeguards.reopen = {ReopenMode::kWidth, 0.5, 3};
  const auto model = makeModel(c, makeRoad(c));
  int healthy = 0, reopened = 0;
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const OfflineResult r =
        runOfflineEstimation(c, synthesizeFromConfig(c, *model, seed), model,
                             EstimationMethod::kOneStep, seed);
    EXPECT_FALSE(r.safeguard_rates.flagged()) << "seed " << seed;
    EXPECT_EQ(r.safeguard_rates.reopened.run.count, r.reopened);
    EXPECT_NEAR(r.safeguard_rates.reopened.run.exposure, 13.5, 1e-9);
    healthy += r.healthy;
    reopened += r.reopened;
  }
  std::printf("load change: %d of 5 seeds healthy, %d re-opens\n", healthy, reopened);
  EXPECT_GE(reopened, 5);  // the change is seen ...
  EXPECT_EQ(healthy, 5);   // ... and stays a load change
}

TEST(SafeguardRateFilter, ExactModelControlsOverFiftySeeds) {
  // The live safeguards on the exact model: the rates flag none of 50 seeds
  // and `healthy` (every check) stays within the 5 % false-alarm budget.
  const EstimatorConfig c = liveBump(100);
  const auto model = makeModel(c, makeRoad(c));
  int unhealthy = 0, rates_flagged = 0;
  long gated = 0, damped = 0, reopened = 0;
  const int seeds = 50;
  for (int seed = 1; seed <= seeds; ++seed) {
    const OfflineResult r = runOfflineEstimation(c, synthesizeFromConfig(c, *model, seed), model,
                                                 EstimationMethod::kOneStep, seed);
    unhealthy += !r.healthy;
    rates_flagged += r.safeguard_rates.flagged();
    gated += r.rejected_samples;
    damped += r.damped_updates;
    reopened += r.reopened;
  }
  std::printf("controls: %d of %d unhealthy, %d flagged by the rates; gated %ld, damped %ld, "
              "re-opens %ld\n", unhealthy, seeds, rates_flagged, gated, damped, reopened);
  EXPECT_EQ(rates_flagged, 0);
  EXPECT_LE(unhealthy, 2);  // <= 5 % of 50 (rounded down: 4 % allowed)
}

TEST(SafeguardRateFilter, AnExactModelAtAHighRateReopensAsOftenAsTheRuleExpects) {
  // 1000 samples over the bump with the live safeguards: the window rule
  // re-opens a correct model by chance. Over 20 seeds the re-opens match the
  // summed chance expectation (Poisson bounds at 99.9 %), and the rate check
  // flags at most one seed.
  const EstimatorConfig c = liveBump(1000);
  const auto model = makeModel(c, makeRoad(c));
  long reopened = 0, flagged = 0;
  double expected_chance = 0.0;
  const int seeds = 20;
  for (int seed = 1; seed <= seeds; ++seed) {
    const OfflineResult r = runOfflineEstimation(c, synthesizeFromConfig(c, *model, seed), model,
                                                 EstimationMethod::kOneStep, seed);
    reopened += r.reopened;
    flagged += r.safeguard_rates.reopened.flagged();
    expected_chance += r.safeguard_rates.reopened.run.expected -
                       r.safeguard_rates.reopened.run.exposure / c.health.reopen_interval;
  }
  std::printf("exact model, 1000 samples x %d seeds: %ld re-opens, %.2f expected by chance, "
              "%ld seeds flagged\n", seeds, reopened, expected_chance, flagged);
  EXPECT_GT(expected_chance, 1.0);
  EXPECT_GT(poissonUpperTail(reopened, expected_chance), 1e-3);         // not too many
  EXPECT_GT(1.0 - poissonUpperTail(reopened + 1, expected_chance), 1e-3);  // nor too few
  EXPECT_LE(flagged, 1);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
