// rostest: bag -> replay_node -> estimator_node (started by the .test with
// config/speed_bump.yaml). The bag holds the paper's speed bump with
// N = 100 samples. Checks that a replay at full speed (no handshake: queues
// alone) and a lossless replay at rate 20 after ~reset both give exactly one
// parameter_estimate per sample, stamped like it, and that every estimate
// (mean, std, PC coefficients) equals estimate_offline --bag on the same bag
// to 1e-9 (same core, deterministic), that ~estimate_batch equals
// estimate_offline --method es_mda, and that diagnostics count 100 samples
// processed, none rejected, none processed with a held road, level OK.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <pc_ekf/ParameterEstimate.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/JointState.h>
#include <std_srvs/Trigger.h>

#include <cmath>
#include <map>
#include <memory>
#include <sstream>

#include "replay_test_support.h"

namespace pc_ekf::test {
namespace {

constexpr std::size_t kSamples = 100;
constexpr double kRelativeTolerance = 1e-9;
const char* kEstimator = "/estimator_node";

// estimate_offline's samples.csv: one row per sample, columns by name.
struct OfflineSamples {
  std::map<std::string, std::size_t> column;
  std::vector<std::vector<double>> rows;
  double at(std::size_t row, const std::string& name) const {
    return rows.at(row).at(column.at(name));
  }
};

OfflineSamples readSamplesCsv(const std::string& path) {
  OfflineSamples out;
  std::vector<std::string> header;
  out.rows = readCsvRows(path, &header);  // health text and the like read as NaN
  for (const auto& name : header) out.column[name] = out.column.size();
  return out;
}

std::vector<ros::Time> sampleStamps(const std::string& bag_path) {
  rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
  std::vector<ros::Time> out;
  for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
    if (auto j = m.instantiate<sensor_msgs::JointState>()) out.push_back(j->header.stamp);
  }
  return out;
}

// |a - b| within kRelativeTolerance of `scale`.
::testing::AssertionResult close(double a, double b, double scale, const std::string& what) {
  if (std::abs(a - b) <= kRelativeTolerance * std::abs(scale)) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << what << ": node " << a << " vs offline " << b
                                       << " (relative " << std::abs(a - b) / std::abs(scale) << ")";
}

// Everything the estimator publishes that the tests look at.
class EstimatorOutputs {
 public:
  EstimatorOutputs() {
    ros::NodeHandle nh;
    estimate_sub_ = nh.subscribe<ParameterEstimate>(
        "parameter_estimate", 100000,
        [this](const ParameterEstimate::ConstPtr& m) { estimates.push_back(*m); });
    batch_sub_ = nh.subscribe<ParameterEstimate>(
        "parameter_estimate/batch", 10,
        [this](const ParameterEstimate::ConstPtr& m) { batch.push_back(*m); });
    diagnostics_sub_ = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
        "/diagnostics", 100, [this](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
          for (const auto& s : m->status) {
            if (s.name.find(kEstimator + 1) != std::string::npos) status[s.name] = s;
          }
        });
  }
  std::vector<ParameterEstimate> estimates, batch;
  std::map<std::string, diagnostic_msgs::DiagnosticStatus> status;  // latest, by name

  // A value of the estimator's "... input" status ("" when absent).
  std::string inputValue(const std::string& key) const {
    for (const auto& [name, s] : status) {
      if (name.size() < 6 || name.compare(name.size() - 6, 6, " input") != 0) continue;
      for (const auto& kv : s.values) {
        if (kv.key == key) return kv.value;
      }
    }
    return "";
  }

 private:
  ros::Subscriber estimate_sub_, batch_sub_, diagnostics_sub_;
};

class ReplayEstimator : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    scratch_ = new ScratchDir;
    // The paper's file with N = 100: the sample count only matters to
    // synthesize_bag (the node and estimate_offline --bag take the bag's).
    std::string text = readText(config("speed_bump.yaml"));
    const std::string from = "\n  samples: 10 ", to = "\n  samples: 100 ";
    ASSERT_NE(text.find(from), std::string::npos);
    text.replace(text.find(from), from.size(), to);
    const std::string config100 = scratch_->file("speed_bump_n100.yaml");
    std::ofstream(config100) << text;

    bag_ = scratch_->file("speed_bump_n100.bag");
    RunResult r = run(*scratch_, PC_EKF_EXE_SYNTHESIZE_BAG,
                      "--config " + quote(config100) + " --output " + quote(bag_));
    ASSERT_EQ(r.status, 0) << r.err;
    const std::string node_config = config("speed_bump.yaml");  // as in the .test
    r = run(*scratch_, PC_EKF_EXE_ESTIMATE_OFFLINE,
            "--config " + quote(node_config) + " --bag " + quote(bag_) + " --out " +
                quote(scratch_->file("one_step")));
    ASSERT_EQ(r.status, 0) << r.err;
    offline_ = new OfflineSamples(readSamplesCsv(scratch_->file("one_step/samples.csv")));
    r = run(*scratch_, PC_EKF_EXE_ESTIMATE_OFFLINE,
            "--config " + quote(node_config) + " --bag " + quote(bag_) + " --method es_mda");
    ASSERT_EQ(r.status, 0) << r.err;
    es_mda_ = new std::map<std::string, JsonParameter>(parseParameters(r.out));
    stamps_ = new std::vector<ros::Time>(sampleStamps(bag_));
  }
  static void TearDownTestSuite() {
    delete stamps_;
    delete es_mda_;
    delete offline_;
    delete scratch_;
  }

  void SetUp() override {
    ASSERT_EQ(stamps_->size(), kSamples);
    ASSERT_EQ(offline_->rows.size(), kSamples);
    ASSERT_TRUE(ros::service::waitForService(std::string(kEstimator) + "/reset", 60000))
        << "estimator_node did not come up";
    std_srvs::Trigger reset;
    ASSERT_TRUE(ros::service::call(std::string(kEstimator) + "/reset", reset));
    ASSERT_TRUE(reset.response.success) << reset.response.message;
  }

  static void replay(const std::vector<std::string>& args, EstimatorOutputs& outputs) {
    static int run = 0;
    const std::string tag = "replay" + std::to_string(run++);
    ChildProcess replay_node(siblingExecutable("replay_node"), args, scratch_->file(tag + ".out"),
                             scratch_->file(tag + ".err"));
    const auto spin = [] { ros::spinOnce(); };
    ASSERT_TRUE(replay_node.waitFor(120.0, spin)) << "replay_node did not finish";
    ASSERT_EQ(replay_node.status(), 0) << replay_node.err();
    spinUntil(120.0, spin, [&] { return outputs.estimates.size() >= kSamples; });
    spinUntil(0.5, spin, [] { return false; });  // a duplicate would arrive now
  }

  // One estimate per sample, in order, each equal to estimate_offline's.
  static void expectOfflineEstimates(const std::vector<ParameterEstimate>& estimates) {
    ASSERT_EQ(estimates.size(), kSamples);
    for (std::size_t k = 0; k < kSamples; ++k) {
      const ParameterEstimate& e = estimates[k];
      ASSERT_EQ(e.header.stamp, (*stamps_)[k]) << "estimate " << k;
      ASSERT_EQ(e.sample_index, k + 1);
      ASSERT_EQ(e.names.size(), 2u);
      for (std::size_t i = 0; i < e.names.size(); ++i) {
        const std::string& p = e.names[i];
        const double mean = offline_->at(k, p + "_mean");
        const std::string at = "sample " + std::to_string(k + 1) + " " + p;
        ASSERT_TRUE(close(e.mean[i], mean, mean, at + " mean"));
        ASSERT_TRUE(close(e.stddev[i], offline_->at(k, p + "_stddev"),
                          offline_->at(k, p + "_stddev"), at + " stddev"));
        for (std::size_t j = 0; j < e.term_count; ++j) {
          // Coefficients near 0 are compared on the scale of the mean.
          ASSERT_TRUE(close(e.coefficients[i * e.term_count + j],
                            offline_->at(k, p + "_c" + std::to_string(j)), mean,
                            at + " c" + std::to_string(j)));
        }
      }
    }
  }

  // The estimator's input counters (cumulative since its start) before a replay.
  static std::map<std::string, long> inputCounters(EstimatorOutputs& outputs) {
    spinUntil(
        15.0, [] { ros::spinOnce(); },
        [&] { return !outputs.inputValue("samples processed").empty(); });
    std::map<std::string, long> out;
    for (const char* key : {"samples processed", "samples received", "samples rejected",
                            "road wait expired", "road received"}) {
      const std::string value = outputs.inputValue(key);
      out[key] = value.empty() ? -1 : std::stol(value);
    }
    return out;
  }

  // The estimator's diagnostics once they report this replay's samples processed.
  static void expectCleanDiagnostics(EstimatorOutputs& outputs,
                                     const std::map<std::string, long>& before) {
    const long processed = before.at("samples processed") + static_cast<long>(kSamples);
    spinUntil(
        15.0, [] { ros::spinOnce(); },
        [&] { return outputs.inputValue("samples processed") == std::to_string(processed); });
    const std::map<std::string, long> after = inputCounters(outputs);
    const auto delta = [&](const char* key) { return after.at(key) - before.at(key); };
    EXPECT_EQ(delta("samples processed"), static_cast<long>(kSamples));
    EXPECT_EQ(delta("samples received"), static_cast<long>(kSamples));
    EXPECT_EQ(delta("samples rejected"), 0);
    EXPECT_EQ(delta("road wait expired"), 0);  // every sample had its road
    EXPECT_EQ(delta("road received"), 3001);
    for (const auto& [name, s] : outputs.status) {
      EXPECT_EQ(s.level, diagnostic_msgs::DiagnosticStatus::OK) << name << ": " << s.message;
    }
  }

  static ScratchDir* scratch_;
  static std::string bag_;
  static OfflineSamples* offline_;
  static std::map<std::string, JsonParameter>* es_mda_;
  static std::vector<ros::Time>* stamps_;
};

ScratchDir* ReplayEstimator::scratch_ = nullptr;
std::string ReplayEstimator::bag_;
OfflineSamples* ReplayEstimator::offline_ = nullptr;
std::map<std::string, JsonParameter>* ReplayEstimator::es_mda_ = nullptr;
std::vector<ros::Time>* ReplayEstimator::stamps_ = nullptr;

TEST_F(ReplayEstimator, FullSpeedReplayGivesEachSampleOneEstimateEqualToOffline) {
  EstimatorOutputs outputs;
  const auto before = inputCounters(outputs);
  // No handshake: only the queues keep this lossless.
  replay({"_bag:=" + bag_, "_rate:=0", "__name:=replay_full_speed"}, outputs);
  expectOfflineEstimates(outputs.estimates);
  expectCleanDiagnostics(outputs, before);
}

TEST_F(ReplayEstimator, LosslessReplayAtRate20MatchesOfflineAndBatchMatchesEsMda) {
  EstimatorOutputs outputs;
  const auto before = inputCounters(outputs);
  replay({"_bag:=" + bag_, "_rate:=20", "_lossless:=true", "__name:=replay_lossless"}, outputs);
  expectOfflineEstimates(outputs.estimates);
  expectCleanDiagnostics(outputs, before);

  std_srvs::Trigger batch;
  ASSERT_TRUE(ros::service::call(std::string(kEstimator) + "/estimate_batch", batch));
  ASSERT_TRUE(batch.response.success) << batch.response.message;
  spinUntil(
      30.0, [] { ros::spinOnce(); }, [&] { return !outputs.batch.empty(); });
  ASSERT_EQ(outputs.batch.size(), 1u);
  const ParameterEstimate& b = outputs.batch.front();
  ASSERT_EQ(b.names.size(), es_mda_->size());
  for (std::size_t i = 0; i < b.names.size(); ++i) {
    const JsonParameter& offline = es_mda_->at(b.names[i]);
    // estimate_offline prints 12 significant digits.
    EXPECT_TRUE(close(b.mean[i], offline.mean, offline.mean, b.names[i] + " batch mean"));
    EXPECT_TRUE(close(b.stddev[i], offline.stddev, offline.stddev, b.names[i] + " batch stddev"));
  }
}

}  // namespace
}  // namespace pc_ekf::test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "replay_estimator_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
