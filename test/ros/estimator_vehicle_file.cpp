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

// The sensitivity the node reports at start (the config's sampling on its
// analytic road) is estimate_offline --sensitivity's on the same record.
TEST(EstimatorVehicleFile, SensitivityOnDiagnosticsEqualsEstimateOffline) {
  ros::NodeHandle nh;
  DiagnosticsWatcher diagnostics(nh);
  const std::string status = "estimator_node: sensitivity";
  const std::string key = "spring_linear_left (largest total index)";
  ASSERT_TRUE(waitUntil([&] { return !diagnostics.value(status, key).empty(); }, 20.0));
  const ToolRun r =
      runCommand(std::string(PC_EKF_EXE_ESTIMATE_OFFLINE) + " --config " + kConfig + " --sensitivity");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json doc = nlohmann::json::parse(r.out);
  ASSERT_EQ(doc.at("sensitivity").size(), 4u);
  for (const auto& row : doc.at("sensitivity")) {
    const std::string name = row.at("name").get<std::string>();
    const std::string shown = diagnostics.value(status, name + " (largest total index)");
    ASSERT_FALSE(shown.empty()) << name;
    EXPECT_NEAR(std::stod(shown), row.at("largest_total").get<double>(),
                1e-5 * row.at("largest_total").get<double>())  // shown with 6 digits
        << name;
  }
  EXPECT_NE(r.err.find("total Sobol indices"), std::string::npos);  // the ranked table
}

}  // namespace
}  // namespace pc_ekf::test

int main(int argc, char** argv) {
  return pc_ekf::test::runRostests(argc, argv, "estimator_vehicle_file_tester");
}
