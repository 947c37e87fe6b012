// Shared by the rostests that replay a bag into estimator_node and compare
// every estimate with estimate_offline --bag's samples.csv (estimator_imu,
// estimator_odom, estimator_road_free): mean, std and every PC coefficient
// to a relative tolerance; and the bag played by `rosbag play` in real time
// (BagIntoNode).
#pragma once

#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <pc_ekf/ParameterEstimate.h>
#include <ros/ros.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "replay_test_support.h"

namespace pc_ekf::test {

inline ::testing::AssertionResult closeToOffline(double a, double b, double scale,
                                                 const std::string& what, double tolerance) {
  if (std::abs(a - b) <= tolerance * std::abs(scale)) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << what << ": node " << a << " vs offline " << b;
}

// `offline`: samples.csv's rows, `column`: its header's columns by name.
inline void compareWithOffline(const std::vector<ParameterEstimate>& estimates,
                               const std::vector<std::vector<double>>& offline,
                               const std::map<std::string, std::size_t>& column,
                               double tolerance) {
  ASSERT_EQ(estimates.size(), offline.size());
  double max_relative = 0.0;
  const auto close = [tolerance](double a, double b, double scale, const std::string& what) {
    return closeToOffline(a, b, scale, what, tolerance);
  };
  for (std::size_t k = 0; k < offline.size(); ++k) {
    const ParameterEstimate& e = estimates[k];
    ASSERT_EQ(e.sample_index, k + 1);
    ASSERT_TRUE(close(e.time, offline[k].at(column.at("t")), 1.0, "t"));
    for (std::size_t i = 0; i < e.names.size(); ++i) {
      const std::string& p = e.names[i];
      const double mean = offline[k].at(column.at(p + "_mean"));
      const std::string at = "sample " + std::to_string(k + 1) + " " + p;
      ASSERT_TRUE(close(e.mean[i], mean, mean, at + " mean"));
      const double sd = offline[k].at(column.at(p + "_stddev"));
      ASSERT_TRUE(close(e.stddev[i], sd, sd, at + " stddev"));
      max_relative = std::max(max_relative, std::abs(e.stddev[i] - sd) / sd);
      for (std::size_t j = 0; j < e.term_count; ++j) {
        ASSERT_TRUE(close(e.coefficients[i * e.term_count + j],
                          offline[k].at(column.at(p + "_c" + std::to_string(j))), mean,
                          at + " c" + std::to_string(j)));
      }
    }
  }
  ::testing::Test::RecordProperty("max_relative_stddev_difference", std::to_string(max_relative));
}

// A bag played into estimator_node by `rosbag play` in real time, without a
// handshake (the node aligns its streams by itself): the estimates, the
// ground truths seen and the values of the diagnostics status whose name
// ends in " <status>" (e.g. "imu", "odom"), kept as they arrive.
class BagIntoNode {
 public:
  explicit BagIntoNode(const std::string& status_name) : suffix_(" " + status_name) {
    estimate_sub_ = nh_.subscribe<ParameterEstimate>(
        "parameter_estimate", 100000,
        [this](const ParameterEstimate::ConstPtr& m) { estimates.push_back(*m); });
    // rosbag play --wait-for-subscribers waits for one on every topic of the bag.
    truth_sub_ = nh_.subscribe<ParameterEstimate>(
        "ground_truth", 10, [this](const ParameterEstimate::ConstPtr&) { ++truths; });
    diagnostics_sub_ = nh_.subscribe<diagnostic_msgs::DiagnosticArray>(
        "/diagnostics", 100, [this](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
          for (const auto& s : m->status) {
            if (s.name.size() > suffix_.size() &&
                s.name.compare(s.name.size() - suffix_.size(), suffix_.size(), suffix_) == 0) {
              for (const auto& kv : s.values) status[kv.key] = kv.value;
            }
          }
        });
  }
  BagIntoNode(const BagIntoNode&) = delete;
  BagIntoNode& operator=(const BagIntoNode&) = delete;

  // Waits for the node, plays `bag` and waits for `samples` estimates (and a
  // second more, in which a duplicate would arrive).
  void play(const ScratchDir& scratch, const std::string& bag, std::size_t samples) {
    ASSERT_TRUE(spinUntil(60.0, spin, [&] { return estimate_sub_.getNumPublishers() > 0; }))
        << "estimator_node did not come up";
    ChildProcess play("/usr/bin/rosbag",
                      {"play", "--quiet", "--wait-for-subscribers", "--rate=1", bag},
                      scratch.file("play.out"), scratch.file("play.err"));
    ASSERT_TRUE(play.waitFor(120.0, spin)) << "rosbag play did not finish";
    ASSERT_EQ(play.status(), 0) << play.err();
    spinUntil(30.0, spin, [&] { return estimates.size() >= samples; });
    spinUntil(1.0, spin, [] { return false; });
  }
  // Waits until the status's `key` reads `value`; false on time-out.
  bool statusReaches(const std::string& key, const std::string& value, double seconds = 15.0) {
    return spinUntil(seconds, spin, [&] { return status.count(key) && status[key] == value; });
  }
  static void spin() { ros::spinOnce(); }

  std::vector<ParameterEstimate> estimates;
  int truths = 0;
  std::map<std::string, std::string> status;

 private:
  std::string suffix_;
  ros::NodeHandle nh_;
  ros::Subscriber estimate_sub_, truth_sub_, diagnostics_sub_;
};

}  // namespace pc_ekf::test
