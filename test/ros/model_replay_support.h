// Shared by the rostests of models other than the paper's roll plane
// (replay_full_car, estimator_plugin_model): synthesise a bag of a config,
// run estimate_offline --bag on it, replay it losslessly into the
// /estimator_node the .test started with the same config, and check that
// every estimate equals estimate_offline's to 1e-9.
#pragma once

#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <pc_ekf/ParameterEstimate.h>
#include <ros/ros.h>
#include <std_srvs/Trigger.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "replay_test_support.h"

namespace pc_ekf::test {

struct ModelReplay {
  std::vector<ParameterEstimate> estimates;
  std::map<std::string, diagnostic_msgs::DiagnosticStatus> status;  // latest, by name
  std::string batch_reply;  // ~estimate_batch's message
  bool batch_ok = false;
  // True when some diagnostics status has `key` equal to `value`.
  bool diagnostic(const std::string& key, const std::string& value) const {
    for (const auto& [name, s] : status) {
      for (const auto& kv : s.values) {
        if (kv.key == key && kv.value == value) return true;
      }
    }
    return false;
  }
};

// Fills `out`; fails the test (ASSERT) on any step or mismatch. `joints` is
// the diagnostics value the node should report once it ran.
inline void replayAgainstOffline(const std::string& config_path, std::size_t samples,
                                 const std::string& joints, ModelReplay* out) {
  ScratchDir scratch;
  const std::string bag = scratch.file("model.bag");
  RunResult r = run(scratch, PC_EKF_EXE_SYNTHESIZE_BAG,
                    "--config " + quote(config_path) + " --output " + quote(bag));
  ASSERT_EQ(r.status, 0) << r.err;
  r = run(scratch, PC_EKF_EXE_ESTIMATE_OFFLINE,
          "--config " + quote(config_path) + " --bag " + quote(bag) + " --out " +
              quote(scratch.file("offline")));
  ASSERT_EQ(r.status, 0) << r.err;
  std::vector<std::string> header;
  const auto rows = readCsvRows(scratch.file("offline/samples.csv"), &header);
  ASSERT_EQ(rows.size(), samples);
  const auto column = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };

  ros::NodeHandle nh;
  ros::Subscriber sub = nh.subscribe<ParameterEstimate>(
      "parameter_estimate", 100000,
      [out](const ParameterEstimate::ConstPtr& m) { out->estimates.push_back(*m); });
  ros::Subscriber diag = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 100, [out](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
        for (const auto& s : m->status) out->status[s.name] = s;
      });
  const auto spin = [] { ros::spinOnce(); };
  ASSERT_TRUE(ros::service::waitForService("/estimator_node/reset", 60000));
  ASSERT_TRUE(spinUntil(30.0, spin, [&] { return sub.getNumPublishers() > 0; }));
  ChildProcess replay(siblingExecutable("replay_node"),
                      {"_bag:=" + bag, "_rate:=20", "_lossless:=true"}, scratch.file("replay.out"),
                      scratch.file("replay.err"));
  ASSERT_TRUE(replay.waitFor(120.0, spin)) << "replay_node did not finish";
  ASSERT_EQ(replay.status(), 0) << replay.err();
  spinUntil(60.0, spin, [&] { return out->estimates.size() >= samples; });
  ASSERT_EQ(out->estimates.size(), samples);

  for (std::size_t k = 0; k < samples; ++k) {
    const ParameterEstimate& e = out->estimates[k];
    for (std::size_t i = 0; i < e.names.size(); ++i) {
      const double mean = rows[k][column(e.names[i] + "_mean")];
      const double sd = rows[k][column(e.names[i] + "_stddev")];
      ASSERT_NEAR(e.mean[i], mean, 1e-9 * std::abs(mean)) << "sample " << k + 1 << " " << e.names[i];
      ASSERT_NEAR(e.stddev[i], sd, 1e-9 * std::abs(sd)) << "sample " << k + 1 << " " << e.names[i];
    }
  }
  std_srvs::Trigger batch;
  ASSERT_TRUE(ros::service::call("/estimator_node/estimate_batch", batch));
  out->batch_ok = batch.response.success;
  out->batch_reply = batch.response.message;
  spinUntil(5.0, spin, [&] { return out->diagnostic("joints", joints); });
}

}  // namespace pc_ekf::test
