#include "pc_ekf/ros/imu_input.h"

#include <algorithm>
#include <cmath>

namespace pc_ekf {
namespace {

std::int64_t ns(const ros::Time& t) { return static_cast<std::int64_t>(t.sec) * 1000000000LL + t.nsec; }

}  // namespace

ImuInput::ImuInput(const EstimatorConfig& config, AlignedStream stream)
    : channels_(stream == AlignedStream::kImu
                    ? imuChannels(config.model_type->channelNames(), config.measurement.channels)
                    : ImuChannels{}),
      speed_channel_(stream == AlignedStream::kOdom
                         ? odomSpeedChannel(config.model_type->channelNames(), config.measurement.channels)
                         : -1),
      label_(stream == AlignedStream::kImu ? "IMU" : "odom"),
      aligner_(config.node.imu_max_gap),
      timeout_(config.node.road_wait_timeout),
      max_pending_(static_cast<std::size_t>(config.node.max_pending_samples)),
      jump_tolerance_ns_(static_cast<std::int64_t>(std::llround(config.node.time_jump_tolerance * 1e9))) {}

std::string ImuInput::addImu(const sensor_msgs::Imu& msg, double now) {
  ++stats_.received;
  stats_.last_message_wall = now;
  return addConversion(readingFromImu(msg, channels_));
}

std::string ImuInput::addOdom(const nav_msgs::Odometry& msg, double now) {
  ++stats_.received;
  stats_.last_message_wall = now;
  return addConversion(readingFromOdometry(msg, speed_channel_));
}

std::string ImuInput::addConversion(ImuConversion c) {
  stats_.problems["unknown_covariance"] += static_cast<std::uint64_t>(c.unknown_covariances);
  std::string problem;
  for (std::size_t i = 0; i < c.problems.size(); ++i) {
    ++stats_.problems[toString(c.problem_kinds[i])];
    problem += (problem.empty() ? "" : "; ") + c.problems[i];
  }
  if (c.empty()) {
    ++stats_.rejected["no_channel"];
    problem = "no usable " + label_ + " channel" + (problem.empty() ? std::string() : ": " + problem);
    stats_.last_problem = problem;
    return problem;
  }
  const std::int64_t stamp = c.reading.stamp_ns;
  if (have_last_ && stamp <= last_stamp_ns_) {
    if (last_stamp_ns_ - stamp > jump_tolerance_ns_) {
      // A looped bag or a restarted clock: alignment starts again.
      ++stats_.rejected["time_jump"];
      problem = "stamp jumped back by " + std::to_string((last_stamp_ns_ - stamp) * 1e-9) +
                " s: " + label_ + " alignment restarted";
      aligner_.reset();
      have_last_ = false;
      mean_interval_ = 0.0;
      intervals_ = 0;
    } else {
      ++stats_.rejected["out_of_order"];
      problem = "stamped " + std::to_string((last_stamp_ns_ - stamp) * 1e-9) +
                " s before the previous message: not used";
      stats_.last_problem = problem;
      return problem;
    }
  }
  if (have_last_) {
    const double interval = (stamp - last_stamp_ns_) * 1e-9;
    if (intervals_ >= 10 && (interval > 2.0 * mean_interval_ || interval < 0.5 * mean_interval_)) {
      ++stats_.rate_changes;
      problem += (problem.empty() ? "" : "; ") + label_ + " interval " +
                 std::to_string(1e3 * interval) + " ms against a mean of " +
                 std::to_string(1e3 * mean_interval_) + " ms (rate change or stop)";
    }
    ++intervals_;
    const double a = intervals_ < 50 ? 1.0 / static_cast<double>(intervals_) : 0.02;
    mean_interval_ += a * (interval - mean_interval_);
    stats_.rate = mean_interval_ > 0.0 ? 1.0 / mean_interval_ : 0.0;
  }
  last_stamp_ns_ = stamp;
  have_last_ = true;
  ++stats_.used;
  aligner_.add(std::move(c.reading));
  if (!problem.empty()) stats_.last_problem = problem;
  return problem;
}

void ImuInput::addSample(const ros::Time& stamp, const Measurement& m, double arrival) {
  if (!(first_arrival_ >= 0.0)) first_arrival_ = arrival;
  pending_.push_back({stamp, m, arrival});
  stats_.waiting = pending_.size();
  stats_.max_waiting = std::max(stats_.max_waiting, pending_.size());
}

ImuReleased ImuInput::alignFront(bool ready) {
  ImuReleased s = std::move(pending_.front());
  pending_.pop_front();
  const std::int64_t stamp = ns(s.stamp);
  const ImuAlignment a = aligner_.align(s.measurement, stamp);
  if (!ready) {
    // The wait ran out: never aligned with later messages, as the bag reader
    // would; the suspension channels go on alone.
    if (a == ImuAlignment::kAligned) {
      // Cannot happen (no reading at or after the stamp), kept for safety.
      ++stats_.samples_aligned;
    }
    return s;
  }
  switch (a) {
    case ImuAlignment::kAligned:
      ++stats_.samples_aligned;
      break;
    case ImuAlignment::kGap:
      ++stats_.samples_without_imu["gap"];
      break;
    case ImuAlignment::kNoBracket:
      ++stats_.samples_without_imu["no_bracket"];
      break;
  }
  return s;
}

std::vector<ImuReleased> ImuInput::release(double now) {
  std::vector<ImuReleased> out;
  while (!pending_.empty()) {
    const std::int64_t stamp = ns(pending_.front().stamp);
    if (aligner_.ready(stamp)) {
      // Offset to the nearest IMU stamp (the reading at/after and the last before).
      const std::int64_t after = aligner_.firstAtOrAfter(stamp);
      const std::int64_t before = aligner_.lastAtOrBefore(stamp);
      std::int64_t offset = stamp - after;
      if (before >= 0 && stamp - before < after - stamp) offset = stamp - before;
      out.push_back(alignFront(true));
      stats_.last_offset = offset * 1e-9;
      stats_.max_abs_offset = std::max(stats_.max_abs_offset, std::abs(stats_.last_offset));
      continue;
    }
    // odom: no message node.road_wait_timeout after the first sample (a
    // vehicle without odometry): a sample goes on at once, not after a wait
    // of its own; the speed is 0 until read (road_free_stream.h).
    if (speed_channel_ >= 0 && stats_.received == 0 && now - first_arrival_ >= timeout_) {
      ++stats_.samples_without_imu["no_message_yet"];
      out.push_back(alignFront(false));
      continue;
    }
    // As the road's wait: time spent computing with IMU messages queued does
    // not count (the wait runs from the sample's arrival and the last message).
    const bool expired = now - pending_.front().arrival >= timeout_ &&
                         (stats_.last_message_wall == 0.0 || now - stats_.last_message_wall >= timeout_);
    const bool full = pending_.size() > max_pending_;
    if (!expired && !full) break;
    ++stats_.samples_without_imu[expired ? "wait_expired" : "queue_full"];
    out.push_back(alignFront(false));
  }
  stats_.waiting = pending_.size();
  return out;
}

void ImuInput::reset() {
  // Samples waiting for the IMU belong to the abandoned run, and so do the
  // buffered IMU messages: a replay from the start must not find them (its
  // first sample could arrive before its first IMU message and be judged
  // against the old ones).
  pending_.clear();
  first_arrival_ = -1.0;
  stats_.waiting = 0;
  aligner_.reset();
  have_last_ = false;
  mean_interval_ = 0.0;
  intervals_ = 0;
}

}  // namespace pc_ekf
