// End-to-end throughput of estimator_node, for
// launch_free_scripts/lib/bench_node.sh: a ROS node that counts the
// estimates on parameter_estimate while replay_node plays a bag into the
// estimator at full speed. Not a Google Benchmark (it needs the graph).
//   ~expect (int)     estimates to wait for
//   ~timeout (s)      give up after this long without a new estimate (default 60)
//   ~ready (path)     touched once the estimator's publisher is connected
//   ~rate (x)         the replay's rate (default 1): stamps advance 1/rate as fast
//   ~lag_file (path)  also write each estimate's stamp and delay (s), one per line
//   ~last_file (path) also write the last estimate (names, mean, stddev) as JSON,
//                     17 digits: compared with estimate_offline's (lib/bench_long.sh)
//   ~linger (s)       keep listening this long after the last expected estimate, so
//                     the node's /diagnostics report has seen every sample (default 0)
// Prints one JSON object: received, first_to_last_s, samples_per_s and
// max_lag_ms: each estimate's delay is its arrival (wall) minus its sample
// stamp (divided by ~rate: the replay's wall time of the stamp); max_lag_ms is the largest delay
// minus the smallest, i.e. how far the estimator fell behind its best case
// (the fixed offset between the bag's stamps and the wall clock cancels).
// Also: load_changed (estimates with load_changed set) and the `time` of each
// (load_changed_at_s); first_time_s and first_arrival_unix (the first estimate's
// drive time and wall clock, to place a wall-clock sample on the drive); the
// node's own /diagnostics figures last seen (diag_max_lag_ms: its input status's
// "max lag (ms)", in stamp time; diag_load_changes), null when none arrived;
// max_lag_at_s (the `time` of the estimate with the largest delay) and
// own_max_lag_ms: the largest time from a joint_states message's arrival here
// to its estimate's, the node's own part of the lag (what the player or the
// machine's scheduling delays reaches both and cancels).
#include <diagnostic_msgs/DiagnosticArray.h>
#include <pc_ekf/ParameterEstimate.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;

struct Counter {
  long received = 0;
  Clock::time_point first, last;
  double min_delay = 1e300, max_delay = -1e300;
  double rate = 1.0;
  std::vector<std::pair<double, double>> delays;  // (stamp, delay), with ~lag_file
  bool keep = false;
  std::vector<double> load_changed_at;  // `time` of the estimates with load_changed
  pc_ekf::ParameterEstimate::ConstPtr last_msg;
  double first_time = 0.0, first_unix = 0.0;
  void onEstimate(const pc_ekf::ParameterEstimate::ConstPtr& msg) {
    last = Clock::now();
    if (received++ == 0) {
      first = last;
      first_time = msg->time;
      first_unix = std::chrono::duration<double>(
                       std::chrono::system_clock::now().time_since_epoch()).count();
    }
    if (msg->load_changed) load_changed_at.push_back(msg->time);
    last_msg = msg;
    const double delay =
        std::chrono::duration<double>(last.time_since_epoch()).count() - msg->header.stamp.toSec() / rate;
    min_delay = std::min(min_delay, delay);
    if (delay > max_delay) {
      max_delay = delay;
      max_lag_at = msg->time;
    }
    if (keep) delays.emplace_back(msg->header.stamp.toSec(), delay);
    // The node's own part: this estimate's arrival minus its joint_states' here.
    const auto input = input_arrival.find(msg->header.stamp.toNSec());
    if (input != input_arrival.end()) {
      own_max = std::max(own_max, std::chrono::duration<double>(last - input->second).count());
      input_arrival.erase(input);
    }
  }
  double max_lag_at = 0.0;  // `time` of the estimate with the largest delay
  std::unordered_map<std::uint64_t, Clock::time_point> input_arrival;  // by stamp, until answered
  double own_max = 0.0;
  // The same delay for the input itself: what the player adds (not the estimator).
  double input_min = 1e300, input_max = -1e300;
  void onInput(const sensor_msgs::JointState::ConstPtr& msg) {
    const Clock::time_point now = Clock::now();
    const double delay = std::chrono::duration<double>(now.time_since_epoch()).count() -
                         msg->header.stamp.toSec() / rate;
    input_arrival.emplace(msg->header.stamp.toNSec(), now);
    input_min = std::min(input_min, delay);
    input_max = std::max(input_max, delay);
  }
  // The node's /diagnostics: the last values of two keys ("" = none seen).
  std::string diag_max_lag, diag_load_changes;
  void onDiagnostics(const diagnostic_msgs::DiagnosticArray::ConstPtr& msg) {
    for (const auto& status : msg->status) {
      const auto ends = [&](const std::string& tail) {
        return status.name.size() >= tail.size() &&
               status.name.compare(status.name.size() - tail.size(), tail.size(), tail) == 0;
      };
      for (const auto& kv : status.values) {
        if (ends(": input") && kv.key == "max lag (ms)") diag_max_lag = kv.value;
        if (ends(": load and clock") && kv.key == "load changes") diag_load_changes = kv.value;
      }
    }
  }
};

// A number from /diagnostics for JSON: as it came when it parses, else null.
std::string jsonNumber(const std::string& text) {
  char* end = nullptr;
  std::strtod(text.c_str(), &end);
  return !text.empty() && end && *end == '\0' ? text : "null";
}

void writeLast(const std::string& path, const pc_ekf::ParameterEstimate& m) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) return;
  std::fprintf(f, "{\"sample_index\": %u, \"time\": %.17g, \"load_changes\": %u, \"parameters\": [",
               m.sample_index, m.time, m.load_changes);
  for (std::size_t i = 0; i < m.names.size() && i < m.mean.size() && i < m.stddev.size(); ++i) {
    std::fprintf(f, "%s{\"name\": \"%s\", \"mean\": %.17g, \"stddev\": %.17g}", i ? ", " : "",
                 m.names[i].c_str(), m.mean[i], m.stddev[i]);
  }
  std::fprintf(f, "]}\n");
  std::fclose(f);
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "bench_node_throughput");
  ros::NodeHandle nh, pnh("~");
  int expect = 0;
  double timeout = 60.0;
  std::string ready;
  pnh.getParam("expect", expect);
  pnh.getParam("timeout", timeout);
  pnh.getParam("ready", ready);
  Counter counter;
  pnh.getParam("rate", counter.rate);
  std::string lag_file;
  pnh.getParam("lag_file", lag_file);
  counter.keep = !lag_file.empty();
  std::string last_file;
  pnh.getParam("last_file", last_file);
  double linger = 0.0;
  pnh.getParam("linger", linger);
  ros::Subscriber sub = nh.subscribe("parameter_estimate", 200000, &Counter::onEstimate, &counter,
                                     ros::TransportHints().tcpNoDelay());
  ros::Subscriber input_sub = nh.subscribe("suspension/joint_states", 200000, &Counter::onInput,
                                           &counter, ros::TransportHints().tcpNoDelay());
  ros::Subscriber diag_sub = nh.subscribe("/diagnostics", 100, &Counter::onDiagnostics, &counter);
  bool announced = false;
  Clock::time_point quiet_since = Clock::now();
  long seen = 0;
  while (ros::ok() && (expect <= 0 || counter.received < expect)) {
    ros::spinOnce();
    if (!announced && sub.getNumPublishers() > 0 && !ready.empty()) {
      std::ofstream(ready.c_str()) << "ready\n";
      announced = true;
    }
    if (counter.received != seen) {
      seen = counter.received;
      quiet_since = Clock::now();
    } else if (std::chrono::duration<double>(Clock::now() - quiet_since).count() > timeout) {
      break;
    }
    ros::WallDuration(0.0002).sleep();
  }
  for (const auto until = Clock::now() + std::chrono::duration<double>(linger);
       ros::ok() && Clock::now() < until;) {
    ros::spinOnce();
    ros::WallDuration(0.01).sleep();
  }
  const double span = counter.received > 1
                          ? std::chrono::duration<double>(counter.last - counter.first).count()
                          : 0.0;
  std::string changed_at;
  for (double t : counter.load_changed_at) {
    changed_at += (changed_at.empty() ? "" : ", ") + std::to_string(t);
  }
  std::printf(
      "{\"received\": %ld, \"expected\": %d, \"first_to_last_s\": %.6f, \"samples_per_s\": "
      "%.3f, \"max_lag_ms\": %.3f, \"input_max_lag_ms\": %.3f, \"load_changed\": %zu, "
      "\"load_changed_at_s\": [%s], \"first_time_s\": %.6f, \"first_arrival_unix\": %.6f, "
      "\"diag_max_lag_ms\": %s, \"diag_load_changes\": %s, \"max_lag_at_s\": %.6f, "
      "\"own_max_lag_ms\": %.3f}\n",
      counter.received, expect, span,
      span > 0.0 ? static_cast<double>(counter.received - 1) / span : 0.0,
      counter.received > 0 ? 1e3 * (counter.max_delay - counter.min_delay) : 0.0,
      counter.input_max > counter.input_min ? 1e3 * (counter.input_max - counter.input_min) : 0.0,
      counter.load_changed_at.size(), changed_at.c_str(), counter.first_time, counter.first_unix,
      jsonNumber(counter.diag_max_lag).c_str(), jsonNumber(counter.diag_load_changes).c_str(),
      counter.max_lag_at, 1e3 * counter.own_max);
  if (!last_file.empty() && counter.last_msg) writeLast(last_file, *counter.last_msg);
  if (counter.keep) {
    std::ofstream out(lag_file.c_str());
    for (const auto& [stamp, delay] : counter.delays) {
      out << std::to_string(stamp) << ' ' << std::to_string(delay - counter.min_delay) << '\n';
    }
  }
  return counter.received >= expect ? 0 : 1;
}
