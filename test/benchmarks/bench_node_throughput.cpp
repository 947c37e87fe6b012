// End-to-end throughput of estimator_node, for
// launch_free_scripts/lib/bench_node.sh: a ROS node that counts the
// estimates on parameter_estimate while replay_node plays a bag into the
// estimator at full speed. Not a Google Benchmark (it needs the graph).
//   ~expect (int)     estimates to wait for
//   ~timeout (s)      give up after this long without a new estimate (default 60)
//   ~ready (path)     touched once the estimator's publisher is connected
//   ~rate (x)         the replay's rate (default 1): stamps advance 1/rate as fast
//   ~lag_file (path)  also write each estimate's stamp and delay (s), one per line
// Prints one JSON object: received, first_to_last_s, samples_per_s and
// max_lag_ms: each estimate's delay is its arrival (wall) minus its sample
// stamp (divided by ~rate: the replay's wall time of the stamp); max_lag_ms is the largest delay
// minus the smallest, i.e. how far the estimator fell behind its best case
// (the fixed offset between the bag's stamps and the wall clock cancels).
#include <pc_ekf/ParameterEstimate.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <string>
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
  void onEstimate(const pc_ekf::ParameterEstimate::ConstPtr& msg) {
    last = Clock::now();
    if (received++ == 0) first = last;
    const double delay =
        std::chrono::duration<double>(last.time_since_epoch()).count() - msg->header.stamp.toSec() / rate;
    min_delay = std::min(min_delay, delay);
    max_delay = std::max(max_delay, delay);
    if (keep) delays.emplace_back(msg->header.stamp.toSec(), delay);
  }
  // The same delay for the input itself: what the player adds (not the estimator).
  double input_min = 1e300, input_max = -1e300;
  void onInput(const sensor_msgs::JointState::ConstPtr& msg) {
    const double delay = std::chrono::duration<double>(Clock::now().time_since_epoch()).count() -
                         msg->header.stamp.toSec() / rate;
    input_min = std::min(input_min, delay);
    input_max = std::max(input_max, delay);
  }
};

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
  ros::Subscriber sub = nh.subscribe("parameter_estimate", 200000, &Counter::onEstimate, &counter,
                                     ros::TransportHints().tcpNoDelay());
  ros::Subscriber input_sub = nh.subscribe("suspension/joint_states", 200000, &Counter::onInput,
                                           &counter, ros::TransportHints().tcpNoDelay());
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
  const double span = counter.received > 1
                          ? std::chrono::duration<double>(counter.last - counter.first).count()
                          : 0.0;
  std::printf(
      "{\"received\": %ld, \"expected\": %d, \"first_to_last_s\": %.6f, \"samples_per_s\": "
      "%.3f, \"max_lag_ms\": %.3f, \"input_max_lag_ms\": %.3f}\n",
      counter.received, expect, span,
      span > 0.0 ? static_cast<double>(counter.received - 1) / span : 0.0,
      counter.received > 0 ? 1e3 * (counter.max_delay - counter.min_delay) : 0.0,
      counter.input_max > counter.input_min ? 1e3 * (counter.input_max - counter.input_min) : 0.0);
  if (counter.keep) {
    std::ofstream out(lag_file.c_str());
    for (const auto& [stamp, delay] : counter.delays) {
      out << std::to_string(stamp) << ' ' << std::to_string(delay - counter.min_delay) << '\n';
    }
  }
  return counter.received >= expect ? 0 : 1;
}
