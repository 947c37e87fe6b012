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

  ros::NodeHandle nh;
  std::vector<ParameterEstimate> estimates;
  std::map<std::string, std::string> odom;  // the estimator's "odom" status values
  ros::Subscriber estimate_sub = nh.subscribe<ParameterEstimate>(
      "parameter_estimate", 100000,
      [&](const ParameterEstimate::ConstPtr& m) { estimates.push_back(*m); });
  int truths = 0;
  ros::Subscriber truth_sub = nh.subscribe<ParameterEstimate>(
      "ground_truth", 10, [&](const ParameterEstimate::ConstPtr&) { ++truths; });
  ros::Subscriber diagnostics_sub = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 100, [&](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
        for (const auto& s : m->status) {
          if (s.name.size() > 5 && s.name.compare(s.name.size() - 5, 5, " odom") == 0) {
            for (const auto& kv : s.values) odom[kv.key] = kv.value;
          }
        }
      });
  const auto spin = [] { ros::spinOnce(); };
  ASSERT_TRUE(spinUntil(60.0, spin, [&] { return estimate_sub.getNumPublishers() > 0; }))
      << "estimator_node did not come up";

  ChildProcess play("/usr/bin/rosbag",
                    {"play", "--quiet", "--wait-for-subscribers", "--rate=1", bag},
                    scratch.file("play.out"), scratch.file("play.err"));
  ASSERT_TRUE(play.waitFor(120.0, spin)) << "rosbag play did not finish";
  ASSERT_EQ(play.status(), 0) << play.err();
  spinUntil(30.0, spin, [&] { return estimates.size() >= kSamples; });
  spinUntil(1.0, spin, [] { return false; });

  ASSERT_EQ(estimates.size(), kSamples) << "samples lost";
  EXPECT_EQ(truths, 1);
  compareWithOffline(estimates, offline, column, kRelativeTolerance);
  if (HasFatalFailure()) return;

  ASSERT_TRUE(spinUntil(15.0, spin, [&] {
    return odom.count("samples aligned") && odom["samples aligned"] == std::to_string(kSamples);
  })) << "diagnostics: " << (odom.count("samples aligned") ? odom["samples aligned"] : "none");
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
