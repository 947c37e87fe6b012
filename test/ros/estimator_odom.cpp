// rostest (estimator_odom.test): a road-free bag (config/turns.yaml
// with speed and gyro_z) with suspension/joint_states, imu/data (gyro_z in
// angular_velocity.z) and odom (nav_msgs/Odometry, the speed) at the sample
// times, played by `rosbag play` in real time without a handshake. No sample
// may be lost, every estimate must equal estimate_offline --bag's to 1e-9,
// and the node's "odom" diagnostics must show every sample aligned.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <pc_ekf/ParameterEstimate.h>
#include <ros/ros.h>

#include <cmath>
#include <map>

#include "offline_comparison.h"
#include "replay_test_support.h"

namespace pc_ekf::test {
namespace {

constexpr std::size_t kSamples = 200;
constexpr double kRelativeTolerance = 1e-9;

std::string odomConfig() { return std::string(PC_EKF_SOURCE_DIR) + "/test/ros/estimator_odom.yaml"; }

TEST(EstimatorOdom, RosbagPlayWithOdomAndYawRateEqualsOffline) {
  ScratchDir scratch;
  const std::string bag = scratch.file("odom.bag");
  RunResult r = run(scratch, PC_EKF_EXE_SYNTHESIZE_BAG,
                    "--config " + quote(odomConfig()) + " --output " + quote(bag));
  ASSERT_EQ(r.status, 0) << r.err;
  ASSERT_NE(r.err.find("odom messages"), std::string::npos) << r.err;
  r = run(scratch, PC_EKF_EXE_ESTIMATE_OFFLINE,
          "--config " + quote(odomConfig()) + " --bag " + quote(bag) + " --out " +
              quote(scratch.file("offline")));
  ASSERT_EQ(r.status, 0) << r.err;
  std::vector<std::string> header;
  const std::vector<std::vector<double>> offline =
      readCsvRows(scratch.file("offline/samples.csv"), &header);
  ASSERT_EQ(offline.size(), kSamples);
  std::map<std::string, std::size_t> column;
  for (const std::string& h : header) column[h] = column.size();

  BagIntoNode node("odom");
  node.play(scratch, bag, kSamples);
  if (HasFatalFailure()) return;
  std::map<std::string, std::string>& odom = node.status;
  const std::vector<ParameterEstimate>& estimates = node.estimates;

  ASSERT_EQ(estimates.size(), kSamples) << "samples lost";
  EXPECT_EQ(node.truths, 1);
  compareWithOffline(estimates, offline, column, kRelativeTolerance);
  if (HasFatalFailure()) return;

  ASSERT_TRUE(node.statusReaches("samples aligned", std::to_string(kSamples)))
      << "diagnostics: " << (odom.count("samples aligned") ? odom["samples aligned"] : "none");
  EXPECT_EQ(odom["samples without odom"], "0");
  EXPECT_EQ(odom["odom messages received"], std::to_string(kSamples));
  EXPECT_NEAR(std::stod(odom["max |stamp offset| (ms)"]), 0.0, 1e-6);
}

}  // namespace
}  // namespace pc_ekf::test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "estimator_odom_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
