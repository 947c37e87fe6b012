// Bad input mixed into a clean stream (docs/method.md §8.4):
// NaN-only, wrong array length, unknown joint, +-Inf, duplicate stamp,
// out-of-order stamp, a stamp far back in time (dropped: reset_on_time_jump
// is false), and bad road messages.
#include <limits>

#include "estimator_test_support.h"

namespace pc_ekf::test {
namespace {

const char* kNode = "/estimator_node";
const std::string kInput = "estimator_node: input";
const double kNan = std::numeric_limits<double>::quiet_NaN();

sensor_msgs::JointState jointState(const ros::Time& stamp, std::vector<std::string> names,
                                   std::vector<double> position, std::vector<double> velocity) {
  sensor_msgs::JointState js;
  js.header.stamp = stamp;
  js.name = std::move(names);
  js.position = std::move(position);
  js.velocity = std::move(velocity);
  return js;
}

class EstimatorBadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    const EstimatorConfig config = loadConfigFile(configPath("speed_bump.yaml"));
    record_ = syntheticRecord(config, config.truth.seed);
    ASSERT_TRUE(input_.waitForEstimator());
    ASSERT_TRUE(waitUntil([&] { return estimates_.connected(); }, 20.0));
    ASSERT_TRUE(
        waitUntil([&] { return !diagnostics_.value(kInput, "samples received").empty(); }, 10.0));
  }
  void reset() { resetEstimator(kNode, estimates_); }
  long counter(const std::string& key) const {
    const std::string v = diagnostics_.value(kInput, key);
    return v.empty() ? 0 : std::stol(v);
  }

  ros::NodeHandle nh_;
  Record record_;
  VehicleInput input_{nh_, ""};
  Collector<ParameterEstimate> estimates_{nh_, "parameter_estimate"};
  DiagnosticsWatcher diagnostics_{nh_};
};

TEST_F(EstimatorBadInput, BadMessagesAreCountedAndDoNotChangeTheEstimates) {
  const ros::Time origin(1000, 0);
  reset();
  input_.record(record_, origin, true);
  ASSERT_TRUE(estimates_.waitForCount(record_.samples.size(), 30.0));
  const auto clean = estimates_.messages();

  // Counters are cumulative: compare with their values now.
  ASSERT_TRUE(diagnostics_.waitForValue(kInput, "samples processed",
                                        std::to_string(record_.samples.size()), 10.0));
  const std::vector<std::string> keys{"samples rejected: no_observed_channel",
                                      "samples rejected: array_length",
                                      "samples rejected: duplicate_stamp",
                                      "samples rejected: out_of_order",
                                      "samples rejected: time_jump",
                                      "elements rejected: unknown_joint",
                                      "elements rejected: non_finite",
                                      "nan elements (not observed)",
                                      "road rejected: non_finite",
                                      "road rejected: duplicate_stamp"};
  std::map<std::string, long> before;
  for (const auto& k : keys) before[k] = counter(k);

  reset();
  const std::string left = "left_suspension", right = "right_suspension";
  std::size_t next_road = 0;
  for (std::size_t k = 0; k < record_.samples.size(); ++k) {
    const Measurement& m = record_.samples[k];
    while (next_road < record_.road.t.size() && record_.road.t[next_road] <= m.time) {
      const ros::Time stamp = stampAt(origin, record_.road.t[next_road]);
      input_.road(stamp, record_.road.left[next_road], record_.road.right[next_road]);
      if (k == 1 && next_road == 400) input_.road(stamp, 0.5, 0.5);  // duplicate stamp
      ++next_road;
    }
    const ros::Time stamp = stampAt(origin, m.time);
    input_.sample(m, stamp);
    const ros::Time between = stampAt(origin, m.time + 0.01);  // before the next sample
    switch (k) {
      case 1:  // NaN everywhere: nothing observed
        input_.raw(jointState(between, {left, right}, {kNan, kNan}, {kNan, kNan}));
        break;
      case 2:  // three positions for two joints
        input_.raw(jointState(between, {left, right}, {0.01, 0.02, 0.03}, {0.1, 0.2}));
        break;
      case 3:  // only a joint the node does not know
        input_.raw(jointState(between, {"front_suspension"}, {0.01}, {0.1}));
        break;
      case 4:  // the same stamp again, other values
        input_.raw(jointState(stamp, {left, right}, {0.05, 0.05}, {0.5, 0.5}));
        break;
      case 5:  // slightly earlier than the last sample
        input_.raw(
            jointState(stampAt(origin, m.time - 0.01), {left, right}, {0.0, 0.0}, {0.0, 0.0}));
        break;
      case 6:  // far back in time (1 s > time_jump_tolerance)
        input_.raw(
            jointState(stampAt(origin, m.time - 1.0), {left, right}, {0.0, 0.0}, {0.0, 0.0}));
        break;
      case 7:  // +Inf, the rest NaN
        input_.raw(jointState(between, {left, right},
                              {std::numeric_limits<double>::infinity(), kNan}, {kNan, kNan}));
        input_.road(between, kNan, 0.0);
        break;
      default:
        break;
    }
  }
  ASSERT_TRUE(estimates_.waitForCount(record_.samples.size(), 30.0));
  ros::WallDuration(0.3).sleep();
  const auto dirty = estimates_.messages();
  ASSERT_EQ(dirty.size(), clean.size());  // nothing lost, nothing extra
  for (std::size_t k = 0; k < clean.size(); ++k) {
    EXPECT_EQ(dirty[k].header.stamp, clean[k].header.stamp) << k;
    EXPECT_EQ(dirty[k].sample_index, clean[k].sample_index) << k;
    EXPECT_EQ(dirty[k].mean, clean[k].mean) << k;  // bit for bit
    EXPECT_EQ(dirty[k].stddev, clean[k].stddev) << k;
    EXPECT_EQ(dirty[k].coefficients, clean[k].coefficients) << k;
  }

  const std::map<std::string, long> expected{{"samples rejected: no_observed_channel", 3},
                                             {"samples rejected: array_length", 1},
                                             {"samples rejected: duplicate_stamp", 1},
                                             {"samples rejected: out_of_order", 1},
                                             {"samples rejected: time_jump", 1},
                                             {"elements rejected: unknown_joint", 1},
                                             {"elements rejected: non_finite", 1},
                                             {"nan elements (not observed)", 7},
                                             {"road rejected: non_finite", 1},
                                             {"road rejected: duplicate_stamp", 1}};
  EXPECT_TRUE(waitUntil(
      [&] {
        return counter("samples rejected: time_jump") > before.at("samples rejected: time_jump");
      },
      10.0));
  for (const auto& kv : expected) {
    EXPECT_EQ(counter(kv.first) - before.at(kv.first), kv.second) << kv.first;
  }
}

TEST_F(EstimatorBadInput, RejectionsRaiseAWarningInDiagnostics) {
  reset();
  input_.record(record_, ros::Time(2000, 0), true);
  ASSERT_TRUE(estimates_.waitForCount(record_.samples.size(), 30.0));
  // Wait for a report with no new rejections: OK.
  ASSERT_TRUE(waitUntil(
      [&] {
        const auto s = diagnostics_.status(kInput);
        return s && s->level == diagnostic_msgs::DiagnosticStatus::OK;
      },
      10.0));
  input_.raw(jointState(stampAt(ros::Time(2000, 0), 100.0), {"left_suspension"}, {0.0, 1.0}, {}));
  EXPECT_TRUE(waitUntil(
      [&] {
        const auto s = diagnostics_.status(kInput);
        return s && s->level == diagnostic_msgs::DiagnosticStatus::WARN;
      },
      10.0));
  EXPECT_NE(diagnostics_.status(kInput)->message.find("rejected"), std::string::npos);
}

}  // namespace
}  // namespace pc_ekf::test

int main(int argc, char** argv) {
  return pc_ekf::test::runRostests(argc, argv, "estimator_bad_input_tester");
}
