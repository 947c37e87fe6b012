// rostest (estimator_imu.test, issue 29): a bag with suspension/joint_states
// at 400 Hz and imu/data (sensor_msgs/Imu) at 200 Hz, the IMU stamps 2 ms
// after a multiple of 5 ms (so never equal to a joint_states stamp), played by
// `rosbag play` in real time without any handshake. No sample may be lost,
// every estimate must equal estimate_offline --bag's on the same bag to 1e-9
// (both align the IMU by filter/imu_alignment.h), and the node's "imu"
// diagnostics must show every sample aligned, the IMU rate and the offsets.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <pc_ekf/ParameterEstimate.h>
#include <ros/ros.h>
#include <std_srvs/Trigger.h>

#include <cmath>
#include <map>
#include <nlohmann/json.hpp>

#include "offline_comparison.h"
#include "replay_test_support.h"

namespace pc_ekf::test {
namespace {

constexpr std::size_t kSamples = 600;
constexpr double kRelativeTolerance = 1e-9;

std::string imuConfig() { return std::string(PC_EKF_SOURCE_DIR) + "/test/ros/estimator_imu.yaml"; }

TEST(EstimatorImu, RosbagPlayWithImuAtItsOwnRateEqualsOffline) {
  ScratchDir scratch;
  const std::string bag = scratch.file("imu.bag");
  RunResult r = run(scratch, PC_EKF_EXE_SYNTHESIZE_BAG,
                    "--config " + quote(imuConfig()) + " --output " + quote(bag) +
                        " --imu-rate 200 --imu-offset 0.002");
  ASSERT_EQ(r.status, 0) << r.err;
  ASSERT_NE(r.err.find("imu/data messages"), std::string::npos) << r.err;
  r = run(scratch, PC_EKF_EXE_ESTIMATE_OFFLINE,
          "--config " + quote(imuConfig()) + " --bag " + quote(bag) + " --out " +
              quote(scratch.file("offline")));
  ASSERT_EQ(r.status, 0) << r.err;
  std::vector<std::string> header;
  const std::vector<std::vector<double>> offline =
      readCsvRows(scratch.file("offline/samples.csv"), &header);
  ASSERT_EQ(offline.size(), kSamples);
  std::map<std::string, std::size_t> column;
  for (const std::string& h : header) column[h] = column.size();
  // Offline without the IMU gives other numbers: the comparison below can fail.
  const std::string no_imu_config = scratch.file("no_imu.yaml");
  {
    std::ifstream in(imuConfig());
    std::ofstream out(no_imu_config);
    for (std::string line; std::getline(in, line);) {
      if (line.rfind("  channels:", 0) == 0) line = "  channels: [u1, u2, v1, v2]";
      if (line.rfind("  sensor_std:", 0) == 0) line = "  sensor_std: [5.0e-4, 5.0e-4, 5.0e-3, 5.0e-3]";
      if (line.rfind("  r_relative:", 0) == 0) line = "  r_relative: 0.01";
      if (line.rfind("  noise_relative:", 0) == 0) line = "  noise_relative: 0.01";
      if (line.rfind("    noise_floor:", 0) == 0) line = "    noise_floor: [5.0e-4, 5.0e-4, 5.0e-3, 5.0e-3]";
      out << line << "\n";
    }
  }
  r = run(scratch, PC_EKF_EXE_ESTIMATE_OFFLINE,
          "--config " + quote(no_imu_config) + " --bag " + quote(bag) + " --out " +
              quote(scratch.file("offline_no_imu")));
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json no_imu = nlohmann::json::parse(r.out);
  const double no_imu_mass_sd = no_imu.at("parameters").at(0).at("stddev").get<double>();
  const double imu_mass_sd = offline.back().at(column.at("added_mass_stddev"));
  EXPECT_LT(imu_mass_sd, 0.9 * no_imu_mass_sd) << "the IMU channels did not tighten M";
  RecordProperty("mass_stddev_with_imu", std::to_string(imu_mass_sd));
  RecordProperty("mass_stddev_without_imu", std::to_string(no_imu_mass_sd));

  // Real time, no handshake: the node must align the two streams by itself.
  BagIntoNode node("imu");
  node.play(scratch, bag, kSamples);
  if (HasFatalFailure()) return;
  std::map<std::string, std::string>& imu = node.status;
  std::vector<ParameterEstimate>& estimates = node.estimates;
  const auto spin = BagIntoNode::spin;

  ASSERT_EQ(estimates.size(), kSamples) << "samples lost";
  EXPECT_EQ(node.truths, 1);
  compareWithOffline(estimates, offline, column, kRelativeTolerance);
  if (HasFatalFailure()) return;

  ASSERT_TRUE(node.statusReaches("samples aligned", std::to_string(kSamples)))
      << "diagnostics: " << (imu.count("samples aligned") ? imu["samples aligned"] : "none");
  EXPECT_EQ(imu["samples without imu"], "0");
  EXPECT_EQ(imu["samples waiting for imu"], "0");
  EXPECT_EQ(imu["imu messages received"], "301");
  EXPECT_NEAR(std::stod(imu["imu rate (Hz, from stamps)"]), 200.0, 0.01);
  // Joint stamps 2.5 k ms, IMU 2 + 5 m ms: the nearest IMU is 2 ms (k even)
  // or 0.5 ms (k odd) away.
  EXPECT_NEAR(std::stod(imu["max |stamp offset| (ms)"]), 2.0, 1e-6);
  EXPECT_EQ(imu["imu rate changes"], "0");
  RecordProperty("imu_rate_hz", imu["imu rate (Hz, from stamps)"]);

  // replay_node with the lossless handshake, as fast as the node answers:
  // the IMU messages a sample needs are published ahead of the next sample.
  std_srvs::Trigger reset;
  ASSERT_TRUE(ros::service::call("/estimator_node/reset", reset)) << "no ~reset";
  spinUntil(2.0, spin, [&] { return !estimates.empty() && estimates.back().sample_index == 0; });
  estimates.clear();
  ChildProcess replay(siblingExecutable("replay_node"),
                      {"_bag:=" + bag, "_rate:=0", "_lossless:=true", "_lossless_timeout:=5",
                       "__name:=replay_imu"},
                      scratch.file("replay.out"), scratch.file("replay.err"));
  ASSERT_TRUE(replay.waitFor(120.0, spin)) << "replay_node did not finish";
  ASSERT_EQ(replay.status(), 0) << replay.err();
  spinUntil(10.0, spin, [&] { return estimates.size() >= kSamples; });
  spinUntil(0.5, spin, [] { return false; });
  ASSERT_EQ(estimates.size(), kSamples) << "samples lost (lossless replay)";
  compareWithOffline(estimates, offline, column, kRelativeTolerance);
  EXPECT_EQ(replay.err().find("going on"), std::string::npos) << "a handshake timed out";
}

}  // namespace
}  // namespace pc_ekf::test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "estimator_imu_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
