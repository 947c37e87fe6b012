// Deferred re-linearisation (filter.relinearize.defer, docs/realtime.md): a
// re-run due after sample k runs on a worker while the filter goes on with
// its old linearisation, and its state replaces the filter's after sample
// k + ceil(defer x k). Checked against that rule computed here by hand: a
// filter without re-linearisation up to the swap, then a filter started at
// the working prior (built here from the trigger sample's estimate) that has
// run samples 1..k + D.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <thread>

#include "pc_ekf/filter/one_step_filter.h"
#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/pc/pc_statistics.h"

namespace pc_ekf {
namespace {

struct BumpRun {
  EstimatorConfig config;
  std::shared_ptr<const PcPropagator> propagator;
  MeasurementSeries data;
};

BumpRun bumpRun(double defer) {
  BumpRun r;
  r.config = loadConfigFile(std::string(PC_EKF_SOURCE_DIR) + "/config/speed_bump.yaml");
  r.config.sampling.samples = 100;
  // vehicle_live.yaml's re-linearisation, deferred.
  r.config.safeguards.relinearize = {0.01, 20.0, 4, 1000, defer};
  const auto model = makeModel(r.config, makeRoad(r.config));
  r.propagator = makePropagator(r.config, model);
  r.data = synthesizeFromConfig(r.config, *model, 1);
  return r;
}

std::vector<StepResult> filterAll(const BumpRun& r, int pause_every = 0) {
  OneStepFilter f(r.propagator, makeOneStepSettings(r.config));
  std::vector<StepResult> out;
  for (std::size_t k = 0; k < r.data.size(); ++k) {
    out.push_back(f.process(r.data[k]));
    // A slow caller: the worker is far ahead at the swap (the result must not change).
    if (pause_every > 0 && k % pause_every == 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  }
  return out;
}

TEST(DeferredRerun, SwapLandsAfterSampleKPlusCeilDeferKWithTheRerunState) {
  const double defer = 0.5;
  const BumpRun run = bumpRun(defer);
  const std::vector<StepResult> deferred = filterAll(run);
  // The first trigger: the first sample reporting a pending re-run.
  std::size_t k = 0;
  while (k < deferred.size() && !deferred[k].rerun_pending) ++k;
  ASSERT_LT(k, deferred.size()) << "no re-linearisation on the bump";
  const int trigger = deferred[k].index;  // k + 1 samples kept
  const int swap = trigger + static_cast<int>(std::ceil(defer * trigger));
  EXPECT_EQ(deferred[k].rerun_swap_after, swap);
  ASSERT_LE(swap, static_cast<int>(run.data.size()));

  // Up to the swap: exactly the filter without re-linearisation.
  EstimatorConfig plain_config = run.config;
  plain_config.safeguards.relinearize.shrink = 0.0;
  OneStepFilter plain(run.propagator, makeOneStepSettings(plain_config));
  StepResult at_trigger;
  for (int i = 0; i < swap - 1; ++i) {
    const StepResult p = plain.process(run.data[i]);
    EXPECT_EQ(p.mean, deferred[i].mean) << "sample " << i + 1;
    EXPECT_FALSE(deferred[i].relinearized);
    if (i + 1 == trigger) at_trigger = p;
  }
  // The working prior of the first restart: the narrowed parameters around
  // the trigger's estimate (width x std), the others at their prior.
  const RelinearizeSettings& rl = run.config.safeguards.relinearize;
  const Eigen::MatrixXd prior = run.propagator->priorState().bottomRows(2);
  const Eigen::VectorXd start = pcStddev(prior);
  Eigen::MatrixXd theta = run.propagator->mapping().workingCoefficients(
      run.propagator->basis(), at_trigger.mean, rl.width * at_trigger.stddev);
  for (int i = 0; i < 2; ++i) {
    if (!(rl.width * at_trigger.stddev[i] < start[i])) theta.row(i) = prior.row(i);
  }
  OneStepFilter rerun(run.propagator, makeOneStepSettings(plain_config));
  rerun.restore(run.propagator->stateFor(theta), 0.0, 0);
  StepResult expected;
  for (int i = 0; i < swap; ++i) expected = rerun.process(run.data[i]);
  const StepResult& got = deferred[swap - 1];
  EXPECT_TRUE(got.relinearized);
  EXPECT_EQ(got.restarts, 1);
  EXPECT_EQ(got.index, swap);
  EXPECT_EQ(got.mean, expected.mean);  // bit for bit
  EXPECT_EQ(got.coefficients, expected.coefficients);
  // The next sample goes on from the swapped-in state.
  EXPECT_EQ(deferred[swap].mean, rerun.process(run.data[swap]).mean);
}

TEST(DeferredRerun, ResultsDoNotDependOnTheWorkersTiming) {
  const BumpRun run = bumpRun(1.0);
  const std::vector<StepResult> a = filterAll(run);
  const std::vector<StepResult> b = filterAll(run, 3);
  ASSERT_EQ(a.size(), b.size());
  int swaps = 0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].coefficients, b[k].coefficients) << "sample " << k + 1;
    swaps += a[k].relinearized;
  }
  EXPECT_GE(swaps, 1);
  EXPECT_EQ(a.back().restarts, b.back().restarts);
}

TEST(DeferredRerun, DeferZeroIsTheInlineRerun) {
  // defer = 0 keeps the re-run in the trigger sample: the paper's filter.
  const BumpRun run = bumpRun(0.0);
  const std::vector<StepResult> r = filterAll(run);
  bool relinearized = false;
  for (const StepResult& s : r) {
    EXPECT_FALSE(s.rerun_pending);
    relinearized = relinearized || s.relinearized;
  }
  EXPECT_TRUE(relinearized);
}

TEST(DeferredRerun, ResetDuringAPendingRerunStartsAfresh) {
  const BumpRun run = bumpRun(1.0);
  const std::vector<StepResult> whole = filterAll(run);
  OneStepFilter f(run.propagator, makeOneStepSettings(run.config));
  bool pending = false;
  for (const Measurement& m : run.data) {
    if (f.process(m).rerun_pending) {
      pending = true;
      break;
    }
  }
  ASSERT_TRUE(pending);
  f.reset();  // cancels the worker
  std::vector<StepResult> again;
  for (const Measurement& m : run.data) again.push_back(f.process(m));
  for (std::size_t k = 0; k < whole.size(); ++k) {
    EXPECT_EQ(again[k].coefficients, whole[k].coefficients) << k;
  }
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
