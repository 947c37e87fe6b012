// rostest: a bag of the load-change course (synthesize_bag, ground truth per
// sample) replayed at full speed into /tracking (drift + re-open +
// re-linearisation) and /fixed
// (constant parameters). After the second bump /tracking is within 3
// reported std of the new mass and healthy, and equals estimate_offline
// --bag with the same settings to 1e-9; /fixed is confidently off and
// flagged.
#include <gtest/gtest.h>
#include <pc_ekf/ParameterEstimate.h>
#include <ros/ros.h>

#include <cmath>
#include <fstream>

#include "replay_test_support.h"

namespace pc_ekf::test {
namespace {

constexpr std::size_t kSamples = 450;
constexpr double kNewMass = 263.26;  // 223.26 + 40 kg from t = 6 s

std::vector<ParameterEstimate>* collect(ros::NodeHandle& nh, const std::string& topic,
                                        std::vector<ros::Subscriber>* subs) {
  auto* out = new std::vector<ParameterEstimate>;
  subs->push_back(nh.subscribe<ParameterEstimate>(
      topic, 100000, [out](const ParameterEstimate::ConstPtr& m) { out->push_back(*m); }));
  return out;
}

TEST(ReplayLoadChange, DriftAndReopenFollowTheNewLoadConstantParametersAreFlagged) {
  ScratchDir scratch;
  const std::string bag = scratch.file("load_change.bag");
  RunResult r = run(scratch, PC_EKF_EXE_SYNTHESIZE_BAG,
                    "--config " + quote(config("load_change_course.yaml")) + " --output " + quote(bag));
  ASSERT_EQ(r.status, 0) << r.err;
  // The node's settings as one file, for estimate_offline.
  const std::string tracking = scratch.file("tracking.yaml");
  std::ofstream(tracking) << readText(config("load_change_course.yaml"))
                          << "\nfilter: {drift: [2.0, 0.0], reopen: {mode: width, width: 0.5, after: 3},"
                             " relinearize: {shrink: 0.01, width: 20.0}}\n";
  r = run(scratch, PC_EKF_EXE_ESTIMATE_OFFLINE, "--config " + quote(tracking) + " --bag " + quote(bag));
  ASSERT_EQ(r.status, 0) << r.err;
  const auto offline = parseParameters(r.out);

  ros::NodeHandle nh;
  std::vector<ros::Subscriber> subs;
  std::unique_ptr<std::vector<ParameterEstimate>> tracked(
      collect(nh, "/tracking/parameter_estimate", &subs));
  std::unique_ptr<std::vector<ParameterEstimate>> fixed(collect(nh, "/fixed/parameter_estimate", &subs));
  const auto spin = [] { ros::spinOnce(); };
  ASSERT_TRUE(spinUntil(60.0, spin, [&] {
    return subs[0].getNumPublishers() > 0 && subs[1].getNumPublishers() > 0;
  }));
  ChildProcess replay(siblingExecutable("replay_node"), {"_bag:=" + bag, "_rate:=0"},
                      scratch.file("replay.out"), scratch.file("replay.err"));
  ASSERT_TRUE(replay.waitFor(120.0, spin)) << "replay_node did not finish";
  ASSERT_EQ(replay.status(), 0) << replay.err();
  spinUntil(120.0, spin, [&] { return tracked->size() >= kSamples && fixed->size() >= kSamples; });
  ASSERT_EQ(tracked->size(), kSamples);
  ASSERT_EQ(fixed->size(), kSamples);

  const ParameterEstimate& t = tracked->back();
  EXPECT_LT(std::abs(t.mean[0] - kNewMass), 3.0 * t.stddev[0]) << t.mean[0] << " +- " << t.stddev[0];
  EXPECT_LT(t.stddev[0], 2.0);
  EXPECT_TRUE(t.healthy);
  for (std::size_t i = 0; i < t.names.size(); ++i) {
    const JsonParameter& o = offline.at(t.names[i]);
    EXPECT_NEAR(t.mean[i], o.mean, 1e-9 * std::abs(o.mean)) << t.names[i];
    EXPECT_NEAR(t.stddev[i], o.stddev, 1e-9 * std::abs(o.stddev) + 1e-12) << t.names[i];
  }
  // The node re-linearised in the first bump (road kept from t = 0) and still
  // equals the offline run above.
  int relinearized = 0;
  for (const auto& e : *tracked) {
    for (const auto& w : e.warnings) relinearized += w.rfind("re-linearised", 0) == 0;
  }
  EXPECT_GE(relinearized, 1);
  const ParameterEstimate& f = fixed->back();
  EXPECT_GT(std::abs(f.mean[0] - kNewMass), 10.0 * f.stddev[0]);
  EXPECT_FALSE(f.healthy);
  int flagged = 0;
  for (const auto& e : *fixed) flagged += !e.healthy;
  RecordProperty("tracking", std::to_string(t.mean[0]) + " +- " + std::to_string(t.stddev[0]));
  RecordProperty("fixed", std::to_string(f.mean[0]) + " +- " + std::to_string(f.stddev[0]) +
                              ", unhealthy samples " + std::to_string(flagged));
}

}  // namespace
}  // namespace pc_ekf::test

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "replay_load_change_tester");
  return RUN_ALL_TESTS();
}
