// estimator_node with vehicle_file: (docs/real_vehicle.md): the node resolves
// the file relative to its config file, as estimate_offline does.
#include "estimator_test_support.h"

namespace pc_ekf::test {
namespace {

const std::string kConfig = std::string(PC_EKF_SOURCE_DIR) + "/test/ros/data/calibrated_live.yaml";

TEST(EstimatorVehicleFile, TolerancesFromTheFileFollowTheLoad) {
  ros::NodeHandle nh;
  const EstimatorConfig config = loadConfigFile(kConfig);
  const Record record = syntheticRecord(config, config.truth.seed);
  VehicleInput input(nh, "");
  Collector<ParameterEstimate> estimates(nh, "parameter_estimate");
  ASSERT_TRUE(input.waitForEstimator());
  ASSERT_TRUE(waitUntil([&] { return estimates.connected(); }, 20.0));
  const ParameterEstimate prior = resetEstimator("/estimator_node", estimates, nullptr);
  ASSERT_EQ(prior.names, (std::vector<std::string>{"added_mass", "added_mass_position",
                                                   "spring_linear_left", "bar_inertia"}));
  EXPECT_DOUBLE_EQ(prior.mean[2], 20100.0);  // the file's value, not the config's
  EXPECT_NEAR(prior.stddev[2], 20100.0 * 0.01 / std::sqrt(5.0), 1e-9);
  EXPECT_DOUBLE_EQ(prior.mean[3], 65.5);
  input.record(record, ros::Time(1000, 0), false);
  ASSERT_TRUE(estimates.waitForCount(record.samples.size(), 30.0));
  const auto offline = estimateOffline("--config " + kConfig);
  expectSameEstimate(estimates.messages().back(), offline, 1e-9, "one_step");
}

}  // namespace
}  // namespace pc_ekf::test

int main(int argc, char** argv) {
  return pc_ekf::test::runRostests(argc, argv, "estimator_vehicle_file_tester");
}
