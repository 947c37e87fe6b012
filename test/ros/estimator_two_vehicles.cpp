// Two estimators in namespaces vehicle_a and vehicle_b, fed different records
// at the same time: each publishes its own estimates, equal to
// estimate_offline on its own data.
#include "estimator_test_support.h"
#include "pc_ekf/ros/bag_io.h"

namespace pc_ekf::test {
namespace {

TEST(EstimatorTwoVehicles, IndependentEstimatesEqualToSingleVehicleRuns) {
  ros::NodeHandle nh;
  const EstimatorConfig bump = loadConfigFile(configPath("speed_bump.yaml"));
  const EstimatorConfig sine = loadConfigFile(configPath("sine_1hz.yaml"));
  const Record a = syntheticRecord(bump, 3), b = syntheticRecord(sine, 1);
  const ros::Time origin_a(1000, 0), origin_b(2000, 250000000);

  // vehicle_a's record as a bag, for estimate_offline --bag (road from the bag).
  const std::string bag = std::filesystem::temp_directory_path().string() + "/pc_ekf_vehicle_a_" +
                          std::to_string(::getpid()) + ".bag";
  BagContents contents;
  contents.origin = origin_a;
  contents.road_contacts = contactsOf(a.road);
  contents.samples = a.samples;
  writeBag(bag, contents);

  VehicleInput input_a(nh, "vehicle_a/"), input_b(nh, "vehicle_b/");
  Collector<ParameterEstimate> estimates_a(nh, "vehicle_a/parameter_estimate");
  Collector<ParameterEstimate> estimates_b(nh, "vehicle_b/parameter_estimate");
  Collector<ParameterEstimate> batch_b(nh, "vehicle_b/parameter_estimate/batch");
  ASSERT_TRUE(input_a.waitForEstimator());
  ASSERT_TRUE(input_b.waitForEstimator());
  ASSERT_TRUE(waitUntil([&] { return estimates_a.connected() && estimates_b.connected(); }, 20.0));

  // Interleaved: b's samples between a's road and samples.
  std::size_t next_road = 0;
  for (std::size_t k = 0; k < a.samples.size(); ++k) {
    while (next_road < a.road.t.size() && a.road.t[next_road] <= a.samples[k].time) {
      input_a.road(stampAt(origin_a, a.road.t[next_road]), a.road.left[next_road],
                   a.road.right[next_road]);
      ++next_road;
    }
    input_b.sample(b.samples[k], stampAt(origin_b, b.samples[k].time));
    input_a.sample(a.samples[k], stampAt(origin_a, a.samples[k].time));
  }
  ASSERT_TRUE(estimates_a.waitForCount(a.samples.size(), 30.0));
  ASSERT_TRUE(estimates_b.waitForCount(b.samples.size(), 30.0));
  ros::WallDuration(0.3).sleep();
  const auto msgs_a = estimates_a.messages(), msgs_b = estimates_b.messages();
  ASSERT_EQ(msgs_a.size(), a.samples.size());
  ASSERT_EQ(msgs_b.size(), b.samples.size());
  for (std::size_t k = 0; k < msgs_a.size(); ++k) {
    EXPECT_EQ(msgs_a[k].header.stamp, stampAt(origin_a, a.samples[k].time));
    EXPECT_EQ(msgs_b[k].header.stamp, stampAt(origin_b, b.samples[k].time));
  }
  expectSameEstimate(msgs_a.back(),
                     estimateOffline("--config " + configPath("speed_bump.yaml") + " --bag " + bag),
                     1e-9, "vehicle_a");
  expectSameEstimate(msgs_b.back(), estimateOffline("--config " + configPath("sine_1hz.yaml")),
                     1e-9, "vehicle_b");
  // Different roads and noise: clearly different numbers.
  EXPECT_GT(std::abs(msgs_a.back().mean[0] - msgs_b.back().mean[0]), 1e-3);

  std_srvs::Trigger::Response response;
  ASSERT_TRUE(callTrigger("/vehicle_b/estimator_node/estimate_batch", &response));
  ASSERT_TRUE(response.success) << response.message;
  EXPECT_NE(response.message.find("whole_set"), std::string::npos) << response.message;
  ASSERT_TRUE(batch_b.waitForCount(1, 10.0));
  EXPECT_EQ(batch_b.messages().back().method, "whole_set");
  expectSameEstimate(
      batch_b.messages().back(),
      estimateOffline("--config " + configPath("sine_1hz.yaml") + " --method whole_set"), 1e-9,
      "vehicle_b whole_set");
  std::filesystem::remove(bag);
}

}  // namespace
}  // namespace pc_ekf::test

int main(int argc, char** argv) {
  return pc_ekf::test::runRostests(argc, argv, "estimator_two_vehicles_tester");
}
