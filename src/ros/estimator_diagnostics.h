// What estimator_node reports on /diagnostics (diagnostic_updater): the
// configuration, the input (rate, samples processed, rejections by reason)
// and the filter's health (docs/method.md §5) with the last update latency.
#pragma once

#include <diagnostic_updater/diagnostic_updater.h>

#include <cstdint>
#include <limits>
#include <map>
#include <string>

#include "pc_ekf/filter/health.h"
#include "pc_ekf/io/start_sensitivity.h"
#include "pc_ekf/io/estimator_config.h"
#include "pc_ekf/ros/imu_input.h"

namespace pc_ekf {

// Cumulative since the node started (not cleared by ~reset).
struct EstimatorCounters {
  std::uint64_t samples_received = 0;   // joint_states messages
  std::uint64_t samples_processed = 0;  // through the filter, one estimate each
  std::uint64_t road_received = 0;
  std::uint64_t road_accepted = 0;
  // Whole joint_states messages not used, by reason (duplicate_stamp,
  // out_of_order, time_jump, before_origin, array_length,
  // no_observed_channel, no_road, filter_refused).
  std::map<std::string, std::uint64_t> samples_rejected;
  // Single values or joints not used (unknown_joint, duplicate_joint, non_finite).
  std::map<std::string, std::uint64_t> elements_rejected;
  std::uint64_t nan_elements = 0;  // NaN = not observed (docs/method.md §8.4), not an error
  // road/profile messages not used (duplicate_stamp, out_of_order, time_jump,
  // non_finite, ignored = analytic road in use).
  std::map<std::string, std::uint64_t> road_rejected;
  std::uint64_t road_wait_expired = 0;   // processed with the road held at its last value
  std::uint64_t non_finite_updates = 0;  // filter state restored (docs/nodes.md)
  std::uint64_t batch_not_kept = 0;      // beyond node.max_batch_samples
  std::uint64_t resets = 0;              // ~reset calls
  std::uint64_t time_jump_resets = 0;    // node.reset_on_time_jump
  std::uint64_t rejectedTotal() const;
};

// The last processed sample, for the health status.
struct LastUpdate {
  bool any = false;
  std::uint32_t sample_index = 0;
  double time = 0.0;     // s since the origin
  double latency = 0.0;  // s from arrival to publication (includes the road wait)
  double compute = 0.0;  // s in the filter
  HealthStatus health;
  bool coherence_flagged = false;
  bool healthy = true;
  bool non_finite = false;
  std::vector<std::string> warnings;
  // Load changes (filter.reopen.mode load) and the clock offset (NaN: none).
  std::uint32_t load_changes = 0;
  double load_change_time = std::numeric_limits<double>::quiet_NaN();
  double load_found_at = std::numeric_limits<double>::quiet_NaN();  // the sample that found it
  std::vector<std::string> load_summary;  // "name: mean +- std" after it
  double clock_offset = std::numeric_limits<double>::quiet_NaN();
  double clock_offset_std = std::numeric_limits<double>::quiet_NaN();
  // measurement.standstill: standing at the last sample, stops recognised,
  // samples taken as standing.
  bool standing = false;
  long stops = 0, standing_samples = 0;
};

// The node's own upkeep (not stored in checkpoints): background checkpoint
// writes and re-registrations with a restarted ROS master.
struct NodeUpkeep {
  std::uint64_t checkpoints_written = 0;
  std::uint64_t checkpoints_superseded = 0;  // replaced by a newer one before written
  std::uint64_t checkpoint_errors = 0;
  std::string last_checkpoint_error;
  std::uint64_t master_restarts = 0;  // new masters registered with
  std::string master_state = "connected";  // or "unreachable"
  int master_pid = 0;
  std::string master_last_change;  // wall time of the last re-registration, "" = none
  std::string master_last_report;  // what it registered
};

// How far processing is behind the input (docs/realtime.md): joint_states
// are taken off the subscription by a receiver thread into the node's own
// queue, so that received and processed can be told apart.
struct NodeBacklog {
  double lag = 0.0;             // s, newest stamp received minus newest stamp processed
  double max_lag = 0.0;         // s, largest lag seen when a sample was processed
  std::size_t queue_depth = 0;  // received, not yet processed
  std::size_t max_queue_depth = 0;
  std::uint64_t queue_overflow = 0;  // dropped: more than node.queue_size waiting
  std::size_t pdf_queue = 0;         // parameter_pdf messages being drawn
  std::uint64_t pdf_dropped = 0;     // not drawn: newer ones came while the queue was full
  int rerun_pending_swap = 0;        // deferred re-run: swap after this sample, 0 = none
  int late_swaps = 0;                // deferred re-runs the filter had to wait for
};

class EstimatorDiagnostics {
 public:
  EstimatorDiagnostics(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& node_name,
                       const EstimatorConfig& config);

  EstimatorCounters& counters() { return counters_; }
  LastUpdate& last() { return last_; }
  NodeUpkeep& upkeep() { return upkeep_; }
  NodeBacklog& backlog() { return backlog_; }
  // Run state shown with the input: origin, road mode, pending samples.
  // `origin`: the stamp of t = 0 as sec.nsec, "" while not set.
  void setRunState(const std::string& road_mode, const std::string& origin, std::size_t pending,
                   std::size_t road_samples);
  // Shown under "sensitivity": each uncertain parameter's largest total Sobol index.
  void setSensitivity(const StartSensitivity& s) { sensitivity_ = s; }
  // imu/data (shown under "imu" when measurement.channels select IMU channels).
  void setImu(const ImuInputStats& stats, double now) {
    imu_ = stats;
    imu_now_ = now;
  }
  // odom (shown under "odom" when measurement.channels select speed).
  void setOdom(const ImuInputStats& stats, double now) {
    odom_ = stats;
    odom_now_ = now;
  }
  void publish() { updater_.force_update(); }
  double period() { return updater_.getPeriod(); }

 private:
  void reportConfiguration(diagnostic_updater::DiagnosticStatusWrapper& s);
  void reportInput(diagnostic_updater::DiagnosticStatusWrapper& s);
  void reportHealth(diagnostic_updater::DiagnosticStatusWrapper& s);
  void reportUpkeep(diagnostic_updater::DiagnosticStatusWrapper& s);
  void reportSensitivity(diagnostic_updater::DiagnosticStatusWrapper& s);
  void reportImu(diagnostic_updater::DiagnosticStatusWrapper& s);  // estimator_diagnostics_imu.cpp
  void reportOdom(diagnostic_updater::DiagnosticStatusWrapper& s);  // estimator_diagnostics_imu.cpp
  // The imu or odom status from `i` (names "imu"/"odom", the topic).
  void reportAligned(diagnostic_updater::DiagnosticStatusWrapper& s, const ImuInputStats& i,
                     double stats_now, const char* name, const char* topic, ros::WallTime& reported_at,
                     std::uint64_t& reported_received);
  // Load changes and the clock offset (estimator_diagnostics_load.cpp).
  void reportLoad(diagnostic_updater::DiagnosticStatusWrapper& s);
  std::uint32_t reported_load_changes_ = 0;

  diagnostic_updater::Updater updater_;
  EstimatorConfig config_;
  EstimatorCounters counters_;
  LastUpdate last_;
  NodeUpkeep upkeep_;
  NodeBacklog backlog_;
  std::uint64_t reported_checkpoint_errors_ = 0;
  // For rates and "new rejections since the last report".
  std::uint64_t reported_received_ = 0, reported_rejected_ = 0, reported_expired_ = 0;
  ros::WallTime reported_at_;
  std::string road_mode_ = "undecided";
  std::string origin_;
  std::size_t pending_ = 0, road_samples_ = 0;
  StartSensitivity sensitivity_;
  ImuInputStats imu_;
  double imu_now_ = 0.0;
  std::uint64_t imu_reported_received_ = 0;
  ros::WallTime imu_reported_at_;
  ImuInputStats odom_;
  double odom_now_ = 0.0;
  std::uint64_t odom_reported_received_ = 0;
  ros::WallTime odom_reported_at_;
};

}  // namespace pc_ekf
