// rostest (estimator_road_free.test): road.source none. A bag with
// suspension/joint_states at 200 Hz and imu/data at 400 Hz and no road topic,
// played by `rosbag play` in real time without any handshake. No sample may
// be lost; every estimate must equal estimate_offline --bag's to 1e-9 (both
// split the samples by io/road_free_stream.h), ~estimate_batch must equal
// estimate_offline --method es_mda, the diagnostics name the road-free mode,
// and after ~reset the same bag gives the same estimates again.
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

constexpr std::size_t kSamples = 400;
constexpr double kRelativeTolerance = 1e-9;

std::string roadFreeConfig() {
  return std::string(PC_EKF_SOURCE_DIR) + "/test/ros/estimator_road_free.yaml";
}

::testing::AssertionResult close(double a, double b, double scale, const std::string& what) {
  return closeToOffline(a, b, scale, what, kRelativeTolerance);
}

TEST(EstimatorRoadFree, RosbagPlayWithoutARoadEqualsOffline) {
  ScratchDir scratch;
  const std::string bag = scratch.file("road_free.bag");
  RunResult r = run(scratch, PC_EKF_EXE_SYNTHESIZE_BAG,
                    "--config " + quote(roadFreeConfig()) + " --output " + quote(bag) +
                        " --imu-rate 400 --imu-offset 0.001");
  ASSERT_EQ(r.status, 0) << r.err;
  // No road topic at all: a vehicle's own recording.
  r = run(scratch, "/usr/bin/rosbag", "info " + quote(bag));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.out.find("road/"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("imu/data"), std::string::npos) << r.out;
  r = run(scratch, PC_EKF_EXE_ESTIMATE_OFFLINE,
          "--config " + quote(roadFreeConfig()) + " --bag " + quote(bag) + " --out " +
              quote(scratch.file("offline")));
  ASSERT_EQ(r.status, 0) << r.err;
  std::vector<std::string> header;
  const std::vector<std::vector<double>> offline =
      readCsvRows(scratch.file("offline/samples.csv"), &header);
  ASSERT_EQ(offline.size(), kSamples);
  std::map<std::string, std::size_t> column;
  for (const std::string& h : header) column[h] = column.size();
  r = run(scratch, PC_EKF_EXE_ESTIMATE_OFFLINE,
          "--config " + quote(roadFreeConfig()) + " --bag " + quote(bag) + " --method es_mda");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json es_mda = nlohmann::json::parse(r.out);

  ros::NodeHandle nh;
  std::vector<ParameterEstimate> estimates, batches;
  std::map<std::string, std::string> input;  // the estimator's "input" status values
  ros::Subscriber estimate_sub = nh.subscribe<ParameterEstimate>(
      "parameter_estimate", 100000,
      [&](const ParameterEstimate::ConstPtr& m) { estimates.push_back(*m); });
  ros::Subscriber batch_sub = nh.subscribe<ParameterEstimate>(
      "parameter_estimate/batch", 10,
      [&](const ParameterEstimate::ConstPtr& m) { batches.push_back(*m); });
  int truths = 0;
  // rosbag play --wait-for-subscribers waits for one on every topic of the bag.
  ros::Subscriber truth_sub = nh.subscribe<ParameterEstimate>(
      "ground_truth", 10, [&](const ParameterEstimate::ConstPtr&) { ++truths; });
  ros::Subscriber diagnostics_sub = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 100, [&](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
        for (const auto& s : m->status) {
          if (s.name.size() > 6 && s.name.compare(s.name.size() - 6, 6, " input") == 0) {
            for (const auto& kv : s.values) input[kv.key] = kv.value;
          }
        }
      });
  const auto spin = [] { ros::spinOnce(); };
  ASSERT_TRUE(spinUntil(60.0, spin, [&] { return estimate_sub.getNumPublishers() > 0; }))
      << "estimator_node did not come up";

  for (int pass = 0; pass < 2; ++pass) {
    // Real time, no handshake, no road: the node needs nothing but the bag.
    ChildProcess play("/usr/bin/rosbag",
                      {"play", "--quiet", "--wait-for-subscribers", "--rate=1", bag},
                      scratch.file("play.out"), scratch.file("play.err"));
    ASSERT_TRUE(play.waitFor(120.0, spin)) << "rosbag play did not finish";
    ASSERT_EQ(play.status(), 0) << play.err();
    spinUntil(30.0, spin, [&] { return estimates.size() >= kSamples; });
    spinUntil(1.0, spin, [] { return false; });  // a duplicate would arrive now
    ASSERT_EQ(estimates.size(), kSamples) << "samples lost, pass " << pass;
    compareWithOffline(estimates, offline, column, kRelativeTolerance);
    if (HasFatalFailure()) return;
    if (pass == 1) break;

    std_srvs::Trigger batch;
    ASSERT_TRUE(ros::service::call("/estimator_node/estimate_batch", batch)) << "no ~estimate_batch";
    ASSERT_TRUE(batch.response.success) << batch.response.message;
    ASSERT_TRUE(spinUntil(10.0, spin, [&] { return !batches.empty(); }));
    const ParameterEstimate& b = batches.back();
    EXPECT_EQ(b.method, "es_mda");
    for (std::size_t i = 0; i < b.names.size(); ++i) {
      const auto& p = es_mda.at("parameters").at(i);
      ASSERT_EQ(b.names[i], p.at("name").get<std::string>());
      const double mean = p.at("mean").get<double>(), sd = p.at("stddev").get<double>();
      EXPECT_TRUE(close(b.mean[i], mean, mean, b.names[i] + " es_mda mean"));
      EXPECT_TRUE(close(b.stddev[i], sd, sd, b.names[i] + " es_mda stddev"));
    }
    ASSERT_TRUE(spinUntil(15.0, spin, [&] {
      return input.count("samples processed") && input["samples processed"] == std::to_string(kSamples);
    }));
    EXPECT_EQ(input["road mode"], "none (road-free: the suspension readings drive the body)");
    EXPECT_EQ(input["road received"], "0");
    // The run starts again: its inputs too (the same bag gives the same numbers).
    std_srvs::Trigger reset;
    ASSERT_TRUE(ros::service::call("/estimator_node/reset", reset)) << "no ~reset";
    spinUntil(2.0, spin, [&] { return !estimates.empty() && estimates.back().sample_index == 0; });
    estimates.clear();
  }
  EXPECT_EQ(truths, 2);
}

}  // namespace
}  // namespace pc_ekf::test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "estimator_road_free_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
