// The nodelet form: nodelet::Loader (what `rosrun nodelet nodelet manager`
// runs) finds pc_ekf/EstimatorNodelet through nodelet_plugins.xml and the
// package export, and the nodelet behaves like estimator_node. In-process so
// the test needs no nodelet executable (Debian: libnodeletlib-tools).
#include <nodelet/loader.h>

#include "estimator_test_support.h"

namespace pc_ekf::test {
namespace {

TEST(EstimatorNodelet, LoadsAndEstimatesLikeTheNode) {
  ros::NodeHandle nh;
  nodelet::Loader loader(false);  // no manager services needed
  ASSERT_TRUE(loader.load("/vehicle_n/estimator", "pc_ekf/EstimatorNodelet", {}, {}));
  EXPECT_EQ(loader.listLoadedNodelets(), std::vector<std::string>{"/vehicle_n/estimator"});

  const EstimatorConfig config = loadConfigFile(configPath("speed_bump.yaml"));
  const Record record = syntheticRecord(config, config.truth.seed);
  VehicleInput input(nh, "vehicle_n/");
  Collector<ParameterEstimate> estimates(nh, "vehicle_n/parameter_estimate");
  ASSERT_TRUE(input.waitForEstimator());
  ASSERT_TRUE(waitUntil([&] { return estimates.connected(); }, 20.0));
  input.record(record, ros::Time(1000, 0), false);
  ASSERT_TRUE(estimates.waitForCount(record.samples.size(), 30.0));
  const auto msgs = estimates.messages();
  EXPECT_EQ(msgs.back().sample_index, record.samples.size());
  expectSameEstimate(msgs.back(), estimateOffline("--config " + configPath("speed_bump.yaml")),
                     1e-9, "nodelet");

  std_srvs::Trigger::Response response;
  ASSERT_TRUE(callTrigger("/vehicle_n/estimator/reset", &response));
  EXPECT_TRUE(response.success);
  EXPECT_TRUE(loader.unload("/vehicle_n/estimator"));
}

TEST(EstimatorNodelet, InvalidConfigurationFailsTheLoad) {
  nodelet::Loader loader(false);
  EXPECT_FALSE(loader.load("/vehicle_bad/estimator", "pc_ekf/EstimatorNodelet", {}, {}));
  EXPECT_TRUE(loader.listLoadedNodelets().empty());
}

}  // namespace
}  // namespace pc_ekf::test

int main(int argc, char** argv) {
  return pc_ekf::test::runRostests(argc, argv, "estimator_nodelet_tester");
}
