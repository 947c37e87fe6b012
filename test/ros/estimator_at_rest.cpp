// A vehicle at rest while the config's road says "bump": zero readings the
// model cannot explain (docs/reliability.md "Failure behaviour"). Before the support rule
// the published mean reached M = -240 kg, d_CG = -1.83 m.
#include "estimator_test_support.h"

namespace pc_ekf::test {
namespace {

TEST(EstimatorAtRest, ZeroReadingsStayInTheSupportAndAreFlagged) {
  ros::NodeHandle nh;
  VehicleInput input(nh, "");
  Collector<ParameterEstimate> estimates(nh, "parameter_estimate");
  ASSERT_TRUE(input.waitForEstimator());
  ASSERT_TRUE(waitUntil([&] { return estimates.connected(); }, 20.0));
  const int count = 40;
  ros::WallRate rate(10.0);
  for (int k = 0; k < count; ++k) {
    sensor_msgs::JointState js;
    js.header.stamp = ros::Time::now();
    js.name = {"left_suspension", "right_suspension"};
    js.position = {0.0, 0.0};
    js.velocity = {0.0, 0.0};
    input.raw(js);
    rate.sleep();
  }
  ASSERT_TRUE(estimates.waitForCount(count, 30.0)) << estimates.size();
  const auto msgs = estimates.messages();
  const EstimatorConfig c = loadConfigFile(configPath("speed_bump.yaml"));
  int unhealthy = 0;
  for (const auto& m : msgs) {
    ASSERT_EQ(m.mean.size(), 2u);
    for (std::size_t i = 0; i < 2; ++i) {
      EXPECT_TRUE(std::isfinite(m.mean[i]) && std::isfinite(m.stddev[i])) << m.sample_index;
      EXPECT_LT(std::abs(m.xi_mean[i]), 1.0) << m.sample_index << " " << m.names[i];
    }
    EXPECT_GT(m.mean[0], 0.0) << "negative mass at sample " << m.sample_index;
    unhealthy += !m.healthy;
  }
  EXPECT_FALSE(msgs.back().healthy);
  EXPECT_GT(unhealthy, count / 2);
  RecordProperty("final", std::to_string(msgs.back().mean[0]) + " kg, " +
                              std::to_string(msgs.back().mean[1]) + " m, unhealthy " +
                              std::to_string(unhealthy) + "/" + std::to_string(msgs.size()));
}

}  // namespace
}  // namespace pc_ekf::test

int main(int argc, char** argv) {
  return pc_ekf::test::runRostests(argc, argv, "estimator_at_rest_tester");
}
