// Degenerate cases of EstimatorRun (docs/reliability.md "Failure behaviour"): each has a
// defined outcome and never puts a NaN on the wire.
#include <limits>

#include "estimator_test_support.h"
#include "pc_ekf/ros/estimator_run.h"

namespace pc_ekf::test {
namespace {

EstimatorConfig speedBump() {
  EstimatorConfig c = loadConfigFile(configPath("speed_bump.yaml"));
  c.node.coherence_check = false;
  return c;
}

void expectFiniteMessage(const ParameterEstimate& e) {
  for (double v : e.mean) EXPECT_TRUE(std::isfinite(v));
  for (double v : e.stddev) EXPECT_TRUE(std::isfinite(v));
  for (double v : e.coefficients) EXPECT_TRUE(std::isfinite(v));
  EXPECT_TRUE(std::isfinite(e.nis));
}

// d_CG = 0.762 (1 + 1.5 xi): prior collocation points with xi < -2/3 put the
// mass before the bar's left end. A prior that leaves the physical domain is
// a start-up error naming the parameter and value (the node exits with it);
// points that drift out later are left out of the projection and reported
// (test_filter_health, and a "forecast:" warning in the message).
TEST(EstimatorDegenerate, PriorOutsideThePhysicalDomainIsRefusedAtStart) {
  EstimatorConfig c = speedBump();
  ASSERT_EQ(c.uncertain[1].name, "added_mass_position");
  c.uncertain[1].relative_range = 1.5;
  try {
    makePropagator(c, makeModel(c, makeRoad(c)))->priorState();  // what the node builds at start
    FAIL() << "a prior outside the domain was accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("added_mass_position"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("outside [0, "), std::string::npos) << e.what();
  }
}

// r_relative = 0: R = r_floor = 1e-300, and a sample at t = 0, where every
// point is exactly at its equilibrium (Y = 0): P_zz + R = 1e-300 against a
// measured 1e-6, numerically singular. The update is refused: the state
// before the sample is kept and the message says why.
TEST(EstimatorDegenerate, SingularInnovationCovarianceKeepsTheStateBeforeTheSample) {
  EstimatorConfig c = speedBump();
  c.measurement.noise.r_relative = 0.0;
  c.measurement.noise.r_floor = 1e-300;
  const auto propagator = makePropagator(c, makeModel(c, makeRoad(c)));
  EstimatorRun run(c, propagator, false);
  const ParameterEstimate prior = run.priorEstimate(ros::Time(0, 0));
  Measurement m;
  m.time = 0.0;
  m.channels = {0 /* u1 */, 1 /* u2 */};
  m.values = Eigen::Vector2d(1e-6, -1e-6);  // noise on a vehicle at rest
  const SampleEstimate e = run.process(m, ros::Time(1, 0));
  EXPECT_TRUE(e.non_finite);
  EXPECT_TRUE(e.estimate.non_finite);
  EXPECT_FALSE(e.estimate.healthy);
  ASSERT_FALSE(e.estimate.warnings.empty());
  EXPECT_NE(e.estimate.warnings.back().find("singular"), std::string::npos);
  EXPECT_EQ(e.estimate.mean, prior.mean);
  EXPECT_EQ(e.estimate.stddev, prior.stddev);
  expectFiniteMessage(e.estimate);
  // The next, informative sample is used normally.
  const Record record = syntheticRecord(speedBump(), 1);
  const SampleEstimate next = run.process(record.samples.back(), ros::Time(2, 0));
  EXPECT_FALSE(next.non_finite);
  EXPECT_LT(next.estimate.stddev[0], prior.stddev[0]);
}

// Two samples with the same time (a zero-length interval) reach the filter
// only through the core (the node rejects a repeated stamp as "duplicate"):
// no forecast, two updates; the second one narrows the distribution further.
TEST(EstimatorDegenerate, ZeroLengthIntervalIsTwoUpdatesAtOneTime) {
  const EstimatorConfig c = speedBump();
  const auto propagator = makePropagator(c, makeModel(c, makeRoad(c)));
  EstimatorRun run(c, propagator, false);
  const Record record = syntheticRecord(c, 1);
  const SampleEstimate first = run.process(record.samples[4], ros::Time(1, 0));
  const SampleEstimate second = run.process(record.samples[4], ros::Time(1, 0));
  EXPECT_FALSE(second.non_finite);
  EXPECT_EQ(second.estimate.sample_index, 2u);
  EXPECT_EQ(second.estimate.time, first.estimate.time);
  EXPECT_LT(second.estimate.stddev[0], first.estimate.stddev[0]);
  expectFiniteMessage(second.estimate);
}

}  // namespace
}  // namespace pc_ekf::test

int main(int argc, char** argv) {
  return pc_ekf::test::runRostests(argc, argv, "estimator_degenerate_tester");
}
