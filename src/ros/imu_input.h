// estimator_node's imu/data stream (issue 29, docs/nodes.md "Clocks"): takes
// sensor_msgs/Imu messages and the converted suspension samples, and hands
// the samples on, in order, with their IMU channels by the rule of
// filter/imu_alignment.h (the bag reader's). A sample waits until an IMU
// message stamped at or after it has arrived, at most node.road_wait_timeout
// of wall clock and node.max_pending_samples samples: then it goes on with
// its suspension channels only (counted). No node handles: unit-testable.
// The same class, built for the odom stream (nav_msgs/Odometry: the speed
// channel), aligns the forward speed by the same rule; the node chains the
// two (imu/data first, then odom), each with its own counts.
#pragma once

#include <ros/time.h>
#include <nav_msgs/Odometry.h>
#include <sensor_msgs/Imu.h>

#include <cstdint>
#include <deque>
#include <map>
#include <string>
#include <vector>

#include "pc_ekf/filter/imu_alignment.h"
#include "pc_ekf/io/estimator_config.h"
#include "pc_ekf/ros/message_conversion.h"

namespace pc_ekf {

// Cumulative since the node started; shown under "<node> imu" on /diagnostics.
struct ImuInputStats {
  std::uint64_t received = 0, used = 0;
  // Whole messages not used: out_of_order (stamp at or before the previous
  // one), time_jump (back by more than node.time_jump_tolerance: alignment
  // restarts), no_channel (no usable value).
  std::map<std::string, std::uint64_t> rejected;
  // Fields or values not used or replaced: non_finite, no_data (-1),
  // bad_covariance; unknown_covariance (all zero: sensor_std used).
  std::map<std::string, std::uint64_t> problems;
  std::uint64_t samples_aligned = 0;
  // Samples that went on without IMU channels: wait_expired, queue_full,
  // gap (IMU messages more than node.imu_max_gap apart: the IMU stopped),
  // no_bracket (no IMU message before the sample); odom only: no_message_yet
  // (no odom message node.road_wait_timeout after the first sample: the
  // sample goes on at once).
  std::map<std::string, std::uint64_t> samples_without_imu;
  double rate = 0.0;               // Hz, from a running mean of the stamp intervals
  std::uint64_t rate_changes = 0;  // intervals outside [0.5, 2] x the running mean
  double last_offset = 0.0;        // s, sample stamp - nearest IMU stamp (last aligned)
  double max_abs_offset = 0.0;     // s
  std::size_t waiting = 0, max_waiting = 0;  // samples waiting for the IMU
  double last_message_wall = 0.0;  // wall-clock s of the last message (0 = none yet)
  std::string last_problem;
};

struct ImuReleased {
  ros::Time stamp;
  Measurement measurement;  // with the IMU channels when aligned
  double arrival = 0.0;
};

// Which stream an ImuInput aligns: imu/data (the IMU channels) or odom
// (the speed channel).
enum class AlignedStream { kImu, kOdom };

class ImuInput {
 public:
  explicit ImuInput(const EstimatorConfig& config, AlignedStream stream = AlignedStream::kImu);
  const ImuChannels& channels() const { return channels_; }
  int speedChannel() const { return speed_channel_; }
  // One imu/data message received at wall-clock `now`; "" or a one-line
  // description of what was not used (for a throttled warning).
  std::string addImu(const sensor_msgs::Imu& msg, double now);
  // One odom message (the odom stream): as addImu.
  std::string addOdom(const nav_msgs::Odometry& msg, double now);
  // A converted suspension sample (without IMU channels), stamps in order.
  void addSample(const ros::Time& stamp, const Measurement& m, double arrival);
  // The samples that can go on now, in stamp order.
  std::vector<ImuReleased> release(double now);
  void reset();
  const ImuInputStats& stats() const { return stats_; }
  std::size_t waiting() const { return pending_.size(); }

 private:
  ImuReleased alignFront(bool ready);
  std::string addConversion(ImuConversion c);
  ImuChannels channels_;
  int speed_channel_ = -1;
  std::string label_;  // "IMU" | "odom" (in the problem texts)
  ImuAligner aligner_;
  double timeout_;
  std::size_t max_pending_;
  std::int64_t jump_tolerance_ns_;
  std::deque<ImuReleased> pending_;
  double first_arrival_ = -1.0;  // wall-clock s of the first sample (-1: none yet)
  std::int64_t last_stamp_ns_ = 0;
  bool have_last_ = false;
  double mean_interval_ = 0.0;
  std::uint64_t intervals_ = 0;
  ImuInputStats stats_;
};

}  // namespace pc_ekf
