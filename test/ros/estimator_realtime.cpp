// rostest (estimator_realtime.test): 3000 samples at 1 kHz replayed in real
// time without the handshake into estimator_node, whose configuration defers
// the re-linearisation re-run to a worker (filter.relinearize.defer 1) and
// draws parameter PDFs from 10^5 draws every 100th sample on its PDF worker.
// No sample may be lost, every estimate must equal estimate_offline --bag's
// (which follows the same deferral rule) to 1e-9, the swap must land on the
// same sample in both (before it both are the filter without re-run, after
// it the re-run's), and every PDF must arrive.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <pc_ekf/ParameterEstimate.h>
#include <pc_ekf/ParameterPdf.h>
#include <ros/ros.h>

#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "replay_test_support.h"

namespace pc_ekf::test {
namespace {

constexpr std::size_t kSamples = 3000;
constexpr double kRelativeTolerance = 1e-9;

std::string realtimeConfig() {
  return std::string(PC_EKF_SOURCE_DIR) + "/test/ros/estimator_realtime.yaml";
}

::testing::AssertionResult close(double a, double b, double scale, const std::string& what) {
  if (std::abs(a - b) <= kRelativeTolerance * std::abs(scale)) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << what << ": node " << a << " vs offline " << b;
}

bool relinearized(const ParameterEstimate& e) {
  for (const std::string& w : e.warnings) {
    if (w.rfind("re-linearised", 0) == 0) return true;
  }
  return false;
}

TEST(EstimatorRealtime, KeepsUpAt1kHzThroughADeferredRerunAndPdfDrawsEqualToOffline) {
  ScratchDir scratch;
  const std::string bag = scratch.file("realtime.bag");
  RunResult r = run(scratch, PC_EKF_EXE_SYNTHESIZE_BAG,
                    "--config " + quote(realtimeConfig()) + " --output " + quote(bag));
  ASSERT_EQ(r.status, 0) << r.err;
  r = run(scratch, PC_EKF_EXE_ESTIMATE_OFFLINE,
          "--config " + quote(realtimeConfig()) + " --bag " + quote(bag) + " --out " +
              quote(scratch.file("offline")));
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json offline_json = nlohmann::json::parse(r.out);
  ASSERT_GE(offline_json.at("relinearized").get<int>(), 1) << "no re-linearisation offline";
  std::vector<std::string> header;
  const std::vector<std::vector<double>> offline =
      readCsvRows(scratch.file("offline/samples.csv"), &header);
  ASSERT_EQ(offline.size(), kSamples);
  std::map<std::string, std::size_t> column;
  for (const std::string& h : header) column[h] = column.size();

  ros::NodeHandle nh;
  std::vector<ParameterEstimate> estimates;
  std::vector<ParameterPdf> pdfs;
  std::map<std::string, std::string> input;  // the estimator's "... input" status values
  ros::Subscriber estimate_sub = nh.subscribe<ParameterEstimate>(
      "parameter_estimate", 100000,
      [&](const ParameterEstimate::ConstPtr& m) { estimates.push_back(*m); });
  ros::Subscriber pdf_sub = nh.subscribe<ParameterPdf>(
      "parameter_pdf", 1000, [&](const ParameterPdf::ConstPtr& m) { pdfs.push_back(*m); });
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
  ASSERT_TRUE(spinUntil(30.0, spin, [&] { return pdf_sub.getNumPublishers() > 0; }));

  // Real time, no handshake: the node must keep up by itself.
  ChildProcess replay(siblingExecutable("replay_node"),
                      {"_bag:=" + bag, "_rate:=1", "_lossless:=false", "__name:=replay_realtime"},
                      scratch.file("replay.out"), scratch.file("replay.err"));
  ASSERT_TRUE(replay.waitFor(120.0, spin)) << "replay_node did not finish";
  ASSERT_EQ(replay.status(), 0) << replay.err();
  spinUntil(60.0, spin, [&] { return estimates.size() >= kSamples && pdfs.size() >= 30; });
  spinUntil(0.5, spin, [] { return false; });  // a duplicate would arrive now

  ASSERT_EQ(estimates.size(), kSamples) << "samples lost";
  std::size_t node_swap = 0;
  for (std::size_t k = 0; k < kSamples; ++k) {
    const ParameterEstimate& e = estimates[k];
    ASSERT_EQ(e.sample_index, k + 1);
    if (relinearized(e) && node_swap == 0) node_swap = k + 1;
    for (std::size_t i = 0; i < e.names.size(); ++i) {
      const std::string& p = e.names[i];
      const double mean = offline[k].at(column.at(p + "_mean"));
      const std::string at = "sample " + std::to_string(k + 1) + " " + p;
      ASSERT_TRUE(close(e.mean[i], mean, mean, at + " mean"));
      const double sd = offline[k].at(column.at(p + "_stddev"));
      ASSERT_TRUE(close(e.stddev[i], sd, sd, at + " stddev"));
      for (std::size_t j = 0; j < e.term_count; ++j) {
        ASSERT_TRUE(close(e.coefficients[i * e.term_count + j],
                          offline[k].at(column.at(p + "_c" + std::to_string(j))), mean,
                          at + " c" + std::to_string(j)));
      }
    }
  }
  // Equal estimates on both sides of it: the swap landed on the same sample.
  ASSERT_GT(node_swap, 0u) << "no deferred re-run swapped in";
  RecordProperty("swap_sample", static_cast<int>(node_swap));

  ASSERT_EQ(pdfs.size(), kSamples / 100);
  for (std::size_t i = 0; i < pdfs.size(); ++i) EXPECT_EQ(pdfs[i].sample_index, 100 * (i + 1));

  ASSERT_TRUE(spinUntil(15.0, spin, [&] {
    return input.count("samples processed") &&
           input["samples processed"] == std::to_string(kSamples);
  }));
  EXPECT_EQ(input["samples rejected"], "0");
  EXPECT_EQ(input["queue overflow (dropped)"], "0");
  RecordProperty("max_lag_ms", input["max lag (ms)"]);
  RecordProperty("max_queue_depth", input["max queue depth"]);
  RecordProperty("late_swaps", input["deferred re-runs waited for"]);
}

}  // namespace
}  // namespace pc_ekf::test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "estimator_realtime_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
