// Shared by the estimator_* rostests: synthetic records from the core,
// publishing them to estimator_node, collecting its outputs, running the
// tools, reading estimate_offline's JSON.
#pragma once

#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <pc_ekf/ParameterEstimate.h>
#include <pc_ekf/ParameterPdf.h>
#include <pc_ekf/RoadProfile.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>
#include <std_srvs/Trigger.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/io/measurement_csv.h"
#include "pc_ekf/ros/message_conversion.h"
#include "rostest_main.h"

namespace pc_ekf::test {

inline std::string configPath(const std::string& name) {
  return std::string(PC_EKF_SOURCE_DIR) + "/config/" + name;
}

// Sleeps in wall time until `done` or `timeout` s; true when done.
inline bool waitUntil(const std::function<bool()>& done, double timeout) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(timeout);
  while (ros::ok() && ros::WallTime::now() < end) {
    if (done()) return true;
    ros::WallDuration(0.005).sleep();
  }
  return done();
}

// The two tracks (left, right) of a roll-plane test road, as road/profile carries them.
struct RoadSeries {
  std::vector<double> t, left, right;
};
inline RoadSeries twoTracks(const ContactSeries& s) {
  return RoadSeries{s.t, s.heights.at(0), s.heights.at(1)};
}
inline ContactSeries contactsOf(const RoadSeries& r) {
  return ContactSeries{r.t, {r.left, r.right}};
}

// A measurement record and its road, times in s since the origin.
struct Record {
  MeasurementSeries samples;
  RoadSeries road;  // at road_rate from t = 0 through the last sample
};

// The config's synthetic data (truth, noise seed) and its analytic road sampled
// like synthesize_bag does.
inline Record syntheticRecord(const EstimatorConfig& c, std::uint64_t seed,
                              double road_rate = 1000.0) {
  const auto road = makeRoad(c);
  const auto model = makeModel(c, road);
  Record r;
  r.samples = synthesizeFromConfig(c, *model, seed);
  const ContactSeries s = sampleContactRoad(*road, r.samples.back().time, road_rate);
  r.road = twoTracks(s);
  return r;
}

// Thread-safe list of the messages received on one topic.
template <class M>
class Collector {
 public:
  Collector(ros::NodeHandle& nh, const std::string& topic)
      : sub_(nh.subscribe(topic, 100000, &Collector::onMessage, this)) {}
  std::vector<M> messages() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return messages_;
  }
  std::size_t size() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return messages_.size();
  }
  void clear() {
    std::lock_guard<std::mutex> lock(mutex_);
    messages_.clear();
  }
  bool waitForCount(std::size_t n, double timeout) const {
    return waitUntil([&] { return size() >= n; }, timeout);
  }
  bool connected() const { return sub_.getNumPublishers() > 0; }

 private:
  void onMessage(const typename M::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    messages_.push_back(*m);
  }
  ros::Subscriber sub_;
  mutable std::mutex mutex_;
  std::vector<M> messages_;
};

// The latest /diagnostics status whose name ends with `suffix`
// ("<node>: input" etc.).
class DiagnosticsWatcher {
 public:
  explicit DiagnosticsWatcher(ros::NodeHandle& nh)
      : sub_(nh.subscribe("/diagnostics", 1000, &DiagnosticsWatcher::onMessage, this)) {}
  std::optional<diagnostic_msgs::DiagnosticStatus> status(const std::string& name) const {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = latest_.find(name);
    if (it == latest_.end()) return std::nullopt;
    return it->second;
  }
  // Value of `key` in status `name`, "" when absent.
  std::string value(const std::string& name, const std::string& key) const {
    const auto s = status(name);
    if (!s) return "";
    for (const auto& kv : s->values) {
      if (kv.key == key) return kv.value;
    }
    return "";
  }
  // Waits until value(name, key) == expected.
  bool waitForValue(const std::string& name, const std::string& key, const std::string& expected,
                    double timeout) const {
    return waitUntil([&] { return value(name, key) == expected; }, timeout);
  }

 private:
  void onMessage(const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& s : m->status) latest_[s.name] = s;
  }
  ros::Subscriber sub_;
  mutable std::mutex mutex_;
  std::map<std::string, diagnostic_msgs::DiagnosticStatus> latest_;
};

// Publishes suspension/joint_states and road/profile under namespace `ns`.
class VehicleInput {
 public:
  VehicleInput(ros::NodeHandle& nh, const std::string& ns)
      : joints_(nh.advertise<sensor_msgs::JointState>(ns + "suspension/joint_states", 100000)),
        road_(nh.advertise<RoadProfile>(ns + "road/profile", 100000)) {}
  bool waitForEstimator(double timeout = 20.0) const {
    return waitUntil(
        [&] { return joints_.getNumSubscribers() > 0 && road_.getNumSubscribers() > 0; }, timeout);
  }
  void sample(const Measurement& m, const ros::Time& stamp) {
    joints_.publish(jointStateFromMeasurement(m, stamp));
  }
  void raw(const sensor_msgs::JointState& js) { joints_.publish(js); }
  void road(const ros::Time& stamp, double left, double right) {
    road_.publish(roadProfileMessage(stamp, left, right));
  }
  // The whole record at full speed, road messages up to each sample first;
  // without road when `with_road` is false.
  void record(const Record& r, const ros::Time& origin, bool with_road) {
    std::size_t next_road = 0;
    for (const Measurement& m : r.samples) {
      while (with_road && next_road < r.road.t.size() && r.road.t[next_road] <= m.time) {
        road(stampAt(origin, r.road.t[next_road]), r.road.left[next_road], r.road.right[next_road]);
        ++next_road;
      }
      sample(m, stampAt(origin, m.time));
    }
  }

 private:
  ros::Publisher joints_, road_;
};

inline bool callTrigger(const std::string& service, std_srvs::Trigger::Response* response) {
  if (!ros::service::waitForService(service, ros::Duration(20.0))) return false;
  std_srvs::Trigger srv;
  const bool ok = ros::service::call(service, srv);
  *response = srv.response;
  return ok;
}

// Calls `node`/reset and waits for the prior it publishes (sample_index 0)
// on `estimates`, which is empty afterwards. Returns the prior.
inline ParameterEstimate resetEstimator(const std::string& node,
                                        Collector<ParameterEstimate>& estimates,
                                        std::string* reply = nullptr) {
  estimates.clear();
  std_srvs::Trigger::Response response;
  EXPECT_TRUE(callTrigger(node + "/reset", &response));
  EXPECT_TRUE(response.success) << response.message;
  if (reply) *reply = response.message;
  ParameterEstimate prior;
  EXPECT_TRUE(waitUntil(
      [&] {
        for (const auto& m : estimates.messages()) {
          if (m.sample_index == 0) prior = m;
        }
        return !prior.names.empty();
      },
      10.0));
  estimates.clear();
  return prior;
}

// ---- tools ----

inline std::string readText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

struct ToolRun {
  int status = -1;
  std::string out, err;
};

// Runs a shell command line, capturing stdout and stderr.
inline ToolRun runCommand(const std::string& command) {
  static int counter = 0;
  const std::string base = std::filesystem::temp_directory_path().string() + "/pc_ekf_rostest_" +
                           std::to_string(::getpid()) + "_" + std::to_string(counter++);
  const int raw = std::system((command + " >" + base + ".out 2>" + base + ".err").c_str());
  ToolRun r;
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  r.out = readText(base + ".out");
  r.err = readText(base + ".err");
  std::filesystem::remove(base + ".out");
  std::filesystem::remove(base + ".err");
  return r;
}

// Directory of this test binary: estimator_node is built beside it (devel/lib/pc_ekf).
inline std::string executableBeside(const std::string& name) {
  return (std::filesystem::read_symlink("/proc/self/exe").parent_path() / name).string();
}

struct JsonParameter {
  double mean = 0.0, stddev = 0.0;
};

// "parameters" entries of estimate_offline's JSON, in order (null = NaN).
inline std::vector<JsonParameter> parseParameters(const std::string& json) {
  const auto number = [](const nlohmann::json& v) {
    return v.is_null() ? std::numeric_limits<double>::quiet_NaN() : v.get<double>();
  };
  std::vector<JsonParameter> out;
  const nlohmann::json doc = nlohmann::json::parse(json);  // outlives the loop
  for (const auto& p : doc.at("parameters")) {
    out.push_back({number(p.at("mean")), number(p.at("stddev"))});
  }
  return out;
}

inline std::vector<JsonParameter> estimateOffline(const std::string& args) {
  const ToolRun r = runCommand(std::string(PC_EKF_EXE_ESTIMATE_OFFLINE) + " " + args);
  EXPECT_EQ(r.status, 0) << r.err;
  return parseParameters(r.out);
}

// |a - b| <= rel * max(|a|, |b|) for every mean and stddev.
inline void expectSameEstimate(const ParameterEstimate& msg, const std::vector<JsonParameter>& ref,
                               double rel, const std::string& what) {
  ASSERT_EQ(msg.mean.size(), ref.size()) << what;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    EXPECT_NEAR(msg.mean[i], ref[i].mean, rel * std::abs(ref[i].mean)) << what << " mean " << i;
    EXPECT_NEAR(msg.stddev[i], ref[i].stddev, rel * std::abs(ref[i].stddev))
        << what << " stddev " << i;
  }
}

}  // namespace pc_ekf::test
