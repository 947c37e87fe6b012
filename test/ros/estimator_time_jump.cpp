// A record played twice with the same stamps and /clock (a looped bag under
// /use_sim_time): stamps and the clock go back by 3 s at the loop.
#include <rosgraph_msgs/Clock.h>

#include "estimator_test_support.h"

namespace pc_ekf::test {
namespace {

const std::string kResetting = "resetting/", kDropping = "dropping/";

class EstimatorTimeJump : public ::testing::Test {
 protected:
  void SetUp() override {
    const EstimatorConfig config = loadConfigFile(configPath("speed_bump.yaml"));
    record_ = syntheticRecord(config, config.truth.seed);
    for (auto* input : {&resetting_, &dropping_}) ASSERT_TRUE(input->waitForEstimator());
    ASSERT_TRUE(waitUntil([&] { return clock_.getNumSubscribers() >= 2; }, 20.0));
    ASSERT_TRUE(waitUntil(
        [&] { return resetting_estimates_.connected() && dropping_estimates_.connected(); }, 20.0));
    resetEstimator("/" + kResetting + "estimator_node", resetting_estimates_);
    resetEstimator("/" + kDropping + "estimator_node", dropping_estimates_);
  }

  // The record to both estimators, /clock following the stamps.
  void play(const ros::Time& origin, bool with_road) {
    std::size_t next_road = 0;
    for (const Measurement& m : record_.samples) {
      while (with_road && next_road < record_.road.t.size() &&
             record_.road.t[next_road] <= m.time) {
        const ros::Time stamp = stampAt(origin, record_.road.t[next_road]);
        tick(stamp);
        for (auto* input : {&resetting_, &dropping_}) {
          input->road(stamp, record_.road.left[next_road], record_.road.right[next_road]);
        }
        ++next_road;
      }
      const ros::Time stamp = stampAt(origin, m.time);
      tick(stamp);
      for (auto* input : {&resetting_, &dropping_}) input->sample(m, stamp);
    }
  }
  void tick(const ros::Time& now) {
    rosgraph_msgs::Clock c;
    c.clock = now;
    clock_.publish(c);
  }
  long counter(const std::string& ns, const std::string& key) const {
    const std::string v = diagnostics_.value(ns + "estimator_node: input", key);
    return v.empty() ? 0 : std::stol(v);
  }

  ros::NodeHandle nh_;
  Record record_;
  ros::Publisher clock_ = nh_.advertise<rosgraph_msgs::Clock>("/clock", 100000);
  VehicleInput resetting_{nh_, kResetting}, dropping_{nh_, kDropping};
  Collector<ParameterEstimate> resetting_estimates_{nh_, kResetting + "parameter_estimate"};
  Collector<ParameterEstimate> dropping_estimates_{nh_, kDropping + "parameter_estimate"};
  DiagnosticsWatcher diagnostics_{nh_};
};

void expectSameRun(const std::vector<ParameterEstimate>& a,
                   const std::vector<ParameterEstimate>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].sample_index, b[k].sample_index) << k;
    EXPECT_EQ(a[k].header.stamp, b[k].header.stamp) << k;
    EXPECT_EQ(a[k].mean, b[k].mean) << k;
    EXPECT_EQ(a[k].stddev, b[k].stddev) << k;
  }
}

TEST_F(EstimatorTimeJump, LoopedRecordWithRoadResetsOrDrops) {
  const ros::Time origin(1000, 0);
  const std::size_t n = record_.samples.size();
  play(origin, true);
  ASSERT_TRUE(resetting_estimates_.waitForCount(n, 30.0));
  ASSERT_TRUE(dropping_estimates_.waitForCount(n, 30.0));
  const auto first = resetting_estimates_.messages();
  expectSameRun(first, dropping_estimates_.messages());
  ASSERT_TRUE(diagnostics_.waitForValue(kDropping + "estimator_node: input", "samples processed",
                                        std::to_string(n), 10.0));
  const long resets = counter(kResetting, "time jump resets");
  const long jumps = counter(kDropping, "samples rejected: time_jump");
  const long late = counter(kDropping, "samples rejected: out_of_order");
  const long repeated = counter(kDropping, "samples rejected: duplicate_stamp");
  const long road_jumps = counter(kDropping, "road rejected: time_jump");
  resetting_estimates_.clear();
  dropping_estimates_.clear();

  play(origin, true);  // the loop: road/profile goes back first
  ASSERT_TRUE(resetting_estimates_.waitForCount(n, 30.0));
  expectSameRun(resetting_estimates_.messages(), first);  // started over from the prior
  EXPECT_TRUE(diagnostics_.waitForValue(kResetting + "estimator_node: input", "time jump resets",
                                        std::to_string(resets + 1), 10.0));
  // The dropping estimator publishes nothing for the stale stamps: samples
  // at t < 2.5 s are more than time_jump_tolerance (0.5 s) behind the last
  // (3.0 s), 2.7 s is out of order, 3.0 s a duplicate.
  EXPECT_TRUE(diagnostics_.waitForValue(kDropping + "estimator_node: input",
                                        "samples rejected: time_jump", std::to_string(jumps + 8),
                                        10.0));
  // The stale samples come last: a diagnostics message may be published
  // between them, so each count is waited for, not read once.
  const auto reaches = [&](const std::string& key, long value) {
    return diagnostics_.waitForValue(kDropping + "estimator_node: input", key,
                                     std::to_string(value), 10.0);
  };
  EXPECT_TRUE(reaches("samples rejected: out_of_order", late + 1))
      << counter(kDropping, "samples rejected: out_of_order");
  EXPECT_TRUE(reaches("samples rejected: duplicate_stamp", repeated + 1))
      << counter(kDropping, "samples rejected: duplicate_stamp");
  EXPECT_TRUE(reaches("road rejected: time_jump", road_jumps + 2500))  // t < 2.5 s
      << counter(kDropping, "road rejected: time_jump");
  EXPECT_EQ(dropping_estimates_.size(), 0u);
}

TEST_F(EstimatorTimeJump, LoopedSamplesWithAnalyticRoadResetOrDrop) {
  const ros::Time origin(5000, 0);
  const std::size_t n = record_.samples.size();
  play(origin, false);
  ASSERT_TRUE(resetting_estimates_.waitForCount(n, 30.0));
  ASSERT_TRUE(dropping_estimates_.waitForCount(n, 30.0));
  const auto first = resetting_estimates_.messages();
  resetting_estimates_.clear();
  dropping_estimates_.clear();
  play(origin, false);  // the first sample of the loop goes back 2.7 s
  ASSERT_TRUE(resetting_estimates_.waitForCount(n, 30.0));
  expectSameRun(resetting_estimates_.messages(), first);
  ros::WallDuration(0.5).sleep();
  EXPECT_EQ(dropping_estimates_.size(), 0u);
}

}  // namespace
}  // namespace pc_ekf::test

int main(int argc, char** argv) {
  return pc_ekf::test::runRostests(argc, argv, "estimator_time_jump_tester");
}
