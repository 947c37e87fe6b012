// estimator_node with the road from the road/profile topic: a synthesize_bag
// record (speed bump, N = 100) published at full speed. The road messages
// replace the config's analytic road and set t = 0, as estimate_offline --bag
// does with the same bag, so the numbers agree to the printed digits.
#include <yaml-cpp/yaml.h>

#include "estimator_test_support.h"
#include "pc_ekf/ros/bag_io.h"

namespace pc_ekf::test {
namespace {

const char* kNode = "/estimator_node";
const std::string kInput = "estimator_node: input";

// One bag for all tests: synthesize_bag on speed_bump.yaml with N = 100.
struct CaseB {
  std::string dir, config, bag;
  BagRecord record;
  CaseB() {
    dir = std::filesystem::temp_directory_path().string() + "/pc_ekf_topic_road_" +
          std::to_string(::getpid());
    std::filesystem::create_directories(dir);
    YAML::Node yaml = YAML::LoadFile(configPath("speed_bump.yaml"));
    yaml["sampling"]["samples"] = 100;
    config = dir + "/case_b.yaml";
    std::ofstream(config) << yaml;
    bag = dir + "/case_b.bag";
    const ToolRun r = runCommand(std::string(PC_EKF_EXE_SYNTHESIZE_BAG) + " --config " + config +
                                 " --output " + bag);
    if (r.status != 0) throw std::runtime_error("synthesize_bag failed: " + r.err);
    record = readBag(bag);
  }
  ~CaseB() { std::filesystem::remove_all(dir); }
  Record asRecord(bool positions_only = false) const {
    Record r{record.samples, twoTracks(record.road_contacts)};
    if (positions_only) {
      for (Measurement& m : r.samples) {  // u1, u2 only
        m.channels = {0 /* u1 */, 1 /* u2 */};
        m.values = m.values.head(2).eval();
      }
    }
    return r;
  }
};

const CaseB& caseB() {
  static const CaseB data;
  return data;
}

class EstimatorTopicRoad : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(input_.waitForEstimator());
    ASSERT_TRUE(waitUntil([&] { return estimates_.connected(); }, 20.0));
    resetEstimator(kNode, estimates_);
  }
  std::vector<ParameterEstimate> run(const Record& r, bool with_road = true) {
    input_.record(r, caseB().record.origin, with_road);
    EXPECT_TRUE(estimates_.waitForCount(r.samples.size(), 40.0));
    return estimates_.messages();
  }

  ros::NodeHandle nh_;
  VehicleInput input_{nh_, ""};
  Collector<ParameterEstimate> estimates_{nh_, "parameter_estimate"};
  Collector<ParameterEstimate> batches_{nh_, "parameter_estimate/batch"};
};

TEST_F(EstimatorTopicRoad, FullSpeedReplayEqualsEstimateOfflineBag) {
  const CaseB& data = caseB();
  ASSERT_EQ(data.record.samples.size(), 100u);
  DiagnosticsWatcher diagnostics(nh_);
  const auto msgs = run(data.asRecord());
  ASSERT_EQ(msgs.size(), 100u);  // one per sample, none lost
  for (std::size_t k = 0; k < msgs.size(); ++k) {
    EXPECT_EQ(msgs[k].header.stamp, stampAt(data.record.origin, data.record.samples[k].time));
    EXPECT_EQ(msgs[k].sample_index, k + 1);
    EXPECT_EQ(msgs[k].time, data.record.samples[k].time);
  }
  const auto offline = estimateOffline("--config " + data.config + " --bag " + data.bag);
  expectSameEstimate(msgs.back(), offline, 1e-9, "one_step --bag");
  ASSERT_EQ(msgs.back().coherence_disagreement.size(), 2u);  // 10 full-rate vs decimated pairs

  char origin[32];
  std::snprintf(origin, sizeof(origin), "%u.%09u", data.record.origin.sec, data.record.origin.nsec);
  EXPECT_TRUE(diagnostics.waitForValue(kInput, "time origin (stamp)", origin, 10.0));
  EXPECT_EQ(diagnostics.value(kInput, "road mode"), "road/profile topic");
  EXPECT_EQ(diagnostics.value(kInput, "road wait expired"), "0");

  std_srvs::Trigger::Response response;
  ASSERT_TRUE(callTrigger(std::string(kNode) + "/estimate_batch", &response));
  ASSERT_TRUE(response.success) << response.message;
  ASSERT_TRUE(batches_.waitForCount(1, 10.0));
  expectSameEstimate(
      batches_.messages().back(),
      estimateOffline("--config " + data.config + " --bag " + data.bag + " --method es_mda"), 1e-9,
      "es_mda --bag");
}

TEST_F(EstimatorTopicRoad, SamplesWaitForLateRoadData) {
  // All samples first, the road afterwards: each sample waits (bounded) in
  // the pending queue until the road covers its stamp; same result as in order.
  const CaseB& data = caseB();
  Record samples_only = data.asRecord();
  input_.record(samples_only, data.record.origin, false);
  ros::WallDuration(0.3).sleep();
  EXPECT_EQ(estimates_.size(), 0u);  // nothing without road data
  const RoadSeries road = twoTracks(data.record.road_contacts);
  for (std::size_t i = 0; i < road.t.size(); ++i) {
    input_.road(stampAt(data.record.origin, road.t[i]), road.left[i], road.right[i]);
  }
  ASSERT_TRUE(estimates_.waitForCount(100, 40.0));
  const auto late = estimates_.messages();
  expectSameEstimate(late.back(), estimateOffline("--config " + data.config + " --bag " + data.bag),
                     1e-9, "late road");
}

TEST_F(EstimatorTopicRoad, RoadThatStopsIsHeldAfterTheWaitTimeout) {
  // Road only up to 1.5 s: the later samples are processed after
  // node.road_wait_timeout (2 s) with the road held, and counted.
  const CaseB& data = caseB();
  DiagnosticsWatcher diagnostics(nh_);
  ASSERT_TRUE(
      waitUntil([&] { return !diagnostics.value(kInput, "road wait expired").empty(); }, 10.0));
  const long expired_before = std::stol(diagnostics.value(kInput, "road wait expired"));
  Record r = data.asRecord();
  const auto cut = std::find_if(r.road.t.begin(), r.road.t.end(), [](double t) { return t > 1.5; });
  const std::size_t keep = static_cast<std::size_t>(cut - r.road.t.begin());
  r.road.t.resize(keep);
  r.road.left.resize(keep);
  r.road.right.resize(keep);
  input_.record(r, data.record.origin, true);
  ASSERT_TRUE(estimates_.waitForCount(50, 20.0));
  ros::WallDuration(0.5).sleep();
  EXPECT_EQ(estimates_.size(), 50u);  // samples after 1.5 s still waiting
  ASSERT_TRUE(estimates_.waitForCount(100, 20.0));
  EXPECT_TRUE(diagnostics.waitForValue(kInput, "road wait expired",
                                       std::to_string(expired_before + 50), 10.0));
  for (const auto& m : estimates_.messages()) EXPECT_TRUE(std::isfinite(m.mean[0]));
}

TEST_F(EstimatorTopicRoad, DisplacementsOnlyGiveFiniteWiderEstimates) {
  const CaseB& data = caseB();
  const auto full = run(data.asRecord());
  ASSERT_EQ(full.size(), 100u);
  resetEstimator(kNode, estimates_);
  const auto partial = run(data.asRecord(true));
  ASSERT_EQ(partial.size(), 100u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_TRUE(std::isfinite(partial.back().mean[i]));
    EXPECT_GT(partial.back().stddev[i], full.back().stddev[i]) << i;
  }
  EXPECT_EQ(partial.back().nis_channels, 2u);
  EXPECT_EQ(full.back().nis_channels, 4u);
}

}  // namespace
}  // namespace pc_ekf::test

int main(int argc, char** argv) {
  return pc_ekf::test::runRostests(argc, argv, "estimator_topic_road_tester");
}
