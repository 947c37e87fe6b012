// rostest: replay_node on its own. A bag from synthesize_bag (speed bump,
// road at 1 kHz, 10 samples, ground truth) is replayed into a namespace;
// this node records every topic and checks that each message arrives exactly
// once, unchanged and in order, at full speed; that ~rate scales the recorded
// timing; that ~lossless holds each sample until the previous one's
// parameter_estimate arrived; and that bad bags and parameters are fatal.
#include <gtest/gtest.h>
#include <pc_ekf/ParameterEstimate.h>
#include <pc_ekf/RoadProfile.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/JointState.h>

#include <cmath>
#include <deque>
#include <fstream>
#include <iterator>
#include <memory>

#include "replay_test_support.h"

namespace pc_ekf::test {
namespace {

// What the bag holds, read with the rosbag API (independent of replay_node).
struct BagMessages {
  std::vector<RoadProfile> road;
  std::vector<sensor_msgs::JointState> joints;
  std::vector<ParameterEstimate> truth;
};

BagMessages readAll(const std::string& path) {
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  BagMessages out;
  for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
    if (auto r = m.instantiate<RoadProfile>()) out.road.push_back(*r);
    if (auto j = m.instantiate<sensor_msgs::JointState>()) out.joints.push_back(*j);
    if (auto t = m.instantiate<ParameterEstimate>()) out.truth.push_back(*t);
  }
  return out;
}

bool sameValues(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!(a[i] == b[i] || (std::isnan(a[i]) && std::isnan(b[i])))) return false;
  }
  return true;
}

// Subscribes the three bag topics under `ns` and keeps everything received.
class Recorder {
 public:
  explicit Recorder(const std::string& ns) {
    ros::NodeHandle nh(ns);
    // Queues hold a whole bag: this node spins only every few milliseconds.
    road_sub_ = nh.subscribe<RoadProfile>(
        "road/profile", 100000, [this](const RoadProfile::ConstPtr& m) { got.road.push_back(*m); });
    joint_sub_ = nh.subscribe<sensor_msgs::JointState>(
        "suspension/joint_states", 100000, [this](const sensor_msgs::JointState::ConstPtr& m) {
          got.joints.push_back(*m);
          joint_arrivals.push_back(ros::WallTime::now());
        });
    truth_sub_ = nh.subscribe<ParameterEstimate>(
        "ground_truth", 100,
        [this](const ParameterEstimate::ConstPtr& m) { got.truth.push_back(*m); });
  }
  BagMessages got;
  std::vector<ros::WallTime> joint_arrivals;
  std::size_t size() const { return got.road.size() + got.joints.size() + got.truth.size(); }

 private:
  ros::Subscriber road_sub_, joint_sub_, truth_sub_;
};

class ReplayPlayback : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    scratch_ = new ScratchDir;
    bag_ = scratch_->file("speed_bump.bag");
    const RunResult r =
        run(*scratch_, PC_EKF_EXE_SYNTHESIZE_BAG,
            "--config " + quote(config("speed_bump.yaml")) + " --output " + quote(bag_));
    ASSERT_EQ(r.status, 0) << r.err;
    expected_ = new BagMessages(readAll(bag_));
  }
  static void TearDownTestSuite() {
    delete expected_;
    delete scratch_;
  }

  // replay_node with `args`, stdout/stderr in the scratch directory.
  static std::unique_ptr<ChildProcess> startReplay(const std::vector<std::string>& args) {
    static int run = 0;
    const std::string tag = "replay" + std::to_string(run++);
    return std::make_unique<ChildProcess>(siblingExecutable("replay_node"), args,
                                          scratch_->file(tag + ".out"),
                                          scratch_->file(tag + ".err"));
  }

  // Waits for replay_node to exit 0 and for `recorder` to hold a whole bag,
  // then spins a little longer so that duplicates would show up.
  static void awaitReplay(ChildProcess& replay, Recorder& recorder, double seconds = 60.0) {
    const auto spin = [] { ros::spinOnce(); };
    ASSERT_TRUE(replay.waitFor(seconds, spin)) << "replay_node did not finish\n" << replay.err();
    ASSERT_EQ(replay.status(), 0) << replay.err();
    const std::size_t total =
        expected_->road.size() + expected_->joints.size() + expected_->truth.size();
    spinUntil(10.0, spin, [&] { return recorder.size() >= total; });
    spinUntil(0.3, spin, [] { return false; });
  }

  static ScratchDir* scratch_;
  static std::string bag_;
  static BagMessages* expected_;
};

ScratchDir* ReplayPlayback::scratch_ = nullptr;
std::string ReplayPlayback::bag_;
BagMessages* ReplayPlayback::expected_ = nullptr;

TEST_F(ReplayPlayback, BagHoldsThePaperData) {
  EXPECT_EQ(expected_->road.size(), 3001u);  // 1 kHz over 3 s, both ends
  EXPECT_EQ(expected_->joints.size(), 10u);
  EXPECT_EQ(expected_->truth.size(), 1u);
}

TEST_F(ReplayPlayback, FullSpeedDeliversEveryMessageOnceUnchangedInOrder) {
  Recorder recorder("car1");
  auto replay = startReplay({"_bag:=" + bag_, "_rate:=0", "_linger:=0.5", "__ns:=car1"});
  awaitReplay(*replay, recorder);

  ASSERT_EQ(recorder.got.road.size(), expected_->road.size());
  ASSERT_EQ(recorder.got.joints.size(), expected_->joints.size());
  ASSERT_EQ(recorder.got.truth.size(), expected_->truth.size());
  for (std::size_t i = 0; i < expected_->road.size(); ++i) {
    const RoadProfile &a = recorder.got.road[i], &b = expected_->road[i];
    ASSERT_EQ(a.header.stamp, b.header.stamp) << "road message " << i;
    ASSERT_EQ(a.left, b.left) << "road message " << i;
    ASSERT_EQ(a.right, b.right) << "road message " << i;
  }
  for (std::size_t i = 0; i < expected_->joints.size(); ++i) {
    const sensor_msgs::JointState &a = recorder.got.joints[i], &b = expected_->joints[i];
    EXPECT_EQ(a.header.stamp, b.header.stamp) << "sample " << i;
    EXPECT_EQ(a.name, b.name) << "sample " << i;
    EXPECT_TRUE(sameValues(a.position, b.position)) << "sample " << i;
    EXPECT_TRUE(sameValues(a.velocity, b.velocity)) << "sample " << i;
  }
  EXPECT_EQ(recorder.got.truth[0].mean, expected_->truth[0].mean);
  EXPECT_NE(replay->out().find("3001 on road/profile"), std::string::npos) << replay->out();
  EXPECT_NE(replay->out().find("10 on suspension/joint_states"), std::string::npos);
}

TEST_F(ReplayPlayback, RateScalesTheRecordedTiming) {
  Recorder recorder("car2");
  auto replay = startReplay({"_bag:=" + bag_, "_rate:=4.0", "_linger:=0.5", "__ns:=car2"});
  awaitReplay(*replay, recorder);
  ASSERT_EQ(recorder.joint_arrivals.size(), 10u);
  // Samples every 0.3 s of bag time -> 0.075 s apart at rate 4; 9 gaps.
  const double span = (recorder.joint_arrivals.back() - recorder.joint_arrivals.front()).toSec();
  EXPECT_GT(span, 9 * 0.075 - 0.02);
  EXPECT_LT(span, 9 * 0.075 + 0.5);  // loose: a loaded machine only delays
}

TEST_F(ReplayPlayback, LosslessHoldsEachSampleUntilItsEstimateArrived) {
  // This node plays the estimator: it answers each sample 0.1 s late.
  constexpr double kAnswerDelay = 0.1;
  Recorder recorder("car3");
  ros::NodeHandle nh("car3");
  ros::Publisher estimates = nh.advertise<ParameterEstimate>("parameter_estimate", 100);
  std::deque<std::pair<ros::WallTime, ros::Time>> due;  // (when, stamp)
  ros::Subscriber answer_sub = nh.subscribe<sensor_msgs::JointState>(
      "suspension/joint_states", 100, [&](const sensor_msgs::JointState::ConstPtr& m) {
        due.emplace_back(ros::WallTime::now() + ros::WallDuration(kAnswerDelay), m->header.stamp);
      });
  const auto spin = [&] {
    ros::spinOnce();
    while (!due.empty() && due.front().first <= ros::WallTime::now()) {
      ParameterEstimate e;
      e.header.stamp = due.front().second;
      estimates.publish(e);
      due.pop_front();
    }
  };
  auto replay = startReplay({"_bag:=" + bag_, "_rate:=0", "_lossless:=true", "_linger:=0.2",
                             "_lossless_timeout:=5.0", "__ns:=car3"});
  ASSERT_TRUE(replay->waitFor(60.0, spin)) << replay->err();
  ASSERT_EQ(replay->status(), 0) << replay->err();
  spinUntil(5.0, spin, [&] { return recorder.got.joints.size() >= 10; });

  ASSERT_EQ(recorder.joint_arrivals.size(), 10u);
  for (std::size_t i = 1; i < recorder.joint_arrivals.size(); ++i) {
    EXPECT_GT((recorder.joint_arrivals[i] - recorder.joint_arrivals[i - 1]).toSec(),
              kAnswerDelay - 0.01)
        << "sample " << i << " was published before sample " << i - 1 << " was answered";
  }
  EXPECT_EQ(recorder.got.road.size(), expected_->road.size());
  EXPECT_NE(replay->out().find("lossless: 10 samples answered"), std::string::npos)
      << replay->out();
  EXPECT_NE(replay->out().find("0 timed out"), std::string::npos);
}

TEST_F(ReplayPlayback, BadBagOrParameterIsFatalAndNamed) {
  const std::string missing = scratch_->file("missing.bag");
  const std::string garbage = scratch_->file("garbage.bag");
  std::ofstream(garbage) << "not a bag\n";
  // The first half of a good bag (a recording cut off mid-write).
  const std::string truncated = scratch_->file("truncated.bag");
  {
    std::ifstream in(bag_, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ofstream(truncated, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  }
  struct Case {
    std::vector<std::string> args;
    std::string expected_in_stderr;
  };
  const std::vector<Case> cases = {
      {{"_bag:=" + missing}, missing + ": no such bag file"},
      {{"_bag:=" + garbage}, garbage + ": corrupt, truncated or unsupported bag"},
      {{"_bag:=" + truncated}, truncated + ": corrupt, truncated or unsupported bag"},
      {{"_bag:=" + bag_, "_rate:=-1.0"}, "rate': value -1"},
      {{}, "bag' is required"},
  };
  int index = 0;
  for (Case c : cases) {
    // `_name:=value` stays on the parameter server: one node name per case.
    c.args.push_back("__name:=replay_bad_" + std::to_string(index++));
    auto replay = startReplay(c.args);
    ASSERT_TRUE(replay->waitFor(20.0, [] {}));
    EXPECT_EQ(replay->status(), 2) << replay->err();
    EXPECT_NE(replay->err().find(c.expected_in_stderr), std::string::npos) << replay->err();
  }
}

}  // namespace
}  // namespace pc_ekf::test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "replay_playback_test");
  ros::NodeHandle nh;  // keeps the node up between the tests' handles
  return RUN_ALL_TESTS();
}
