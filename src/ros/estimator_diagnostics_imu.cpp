// The "imu" status of estimator_node (issue 29): kept apart from
// estimator_diagnostics.cpp's other statuses.
#include <diagnostic_msgs/DiagnosticStatus.h>

#include <numeric>
#include <sstream>

#include "pc_ekf/ros/estimator_diagnostics.h"

namespace pc_ekf {

void EstimatorDiagnostics::reportImu(diagnostic_updater::DiagnosticStatusWrapper& s) {
  const ImuInputStats& i = imu_;
  const auto total = [](const std::map<std::string, std::uint64_t>& m) {
    std::uint64_t n = 0;
    for (const auto& kv : m) n += kv.second;
    return n;
  };
  const ros::WallTime now = ros::WallTime::now();
  const double elapsed = (now - imu_reported_at_).toSec();
  const double received_rate =
      imu_reported_at_.isZero() || elapsed <= 0.0
          ? 0.0
          : static_cast<double>(i.received - imu_reported_received_) / elapsed;
  imu_reported_at_ = now;
  imu_reported_received_ = i.received;
  const double silent = i.last_message_wall > 0.0 ? imu_now_ - i.last_message_wall : -1.0;

  std::ostringstream m;
  unsigned char level = diagnostic_msgs::DiagnosticStatus::OK;
  if (i.received == 0) {
    level = diagnostic_msgs::DiagnosticStatus::WARN;
    m << "no imu/data message yet";
  } else if (silent > config_.node.road_wait_timeout) {
    level = diagnostic_msgs::DiagnosticStatus::WARN;
    m << "imu/data silent for " << silent << " s";
  } else {
    m << i.samples_aligned << " samples aligned, IMU at " << i.rate << " Hz";
  }
  const std::uint64_t without = total(i.samples_without_imu);
  if (without > 0) {
    m << "; " << without << " samples without IMU channels";
    level = std::max<unsigned char>(level, diagnostic_msgs::DiagnosticStatus::WARN);
  }
  s.summary(level, m.str());
  s.add("imu rate (Hz, from stamps)", i.rate);
  s.add("imu messages/s received", received_rate);
  s.add("imu rate changes", i.rate_changes);
  s.add("imu messages received", i.received);
  s.add("imu messages used", i.used);
  for (const auto& kv : i.rejected) s.add("imu rejected: " + kv.first, kv.second);
  for (const auto& kv : i.problems) s.add("imu problems: " + kv.first, kv.second);
  s.add("stamp offset (ms, sample - nearest imu)", 1e3 * i.last_offset);
  s.add("max |stamp offset| (ms)", 1e3 * i.max_abs_offset);
  s.add("samples waiting for imu", i.waiting);
  s.add("max samples waiting for imu", i.max_waiting);
  s.add("samples aligned", i.samples_aligned);
  s.add("samples without imu", without);
  for (const auto& kv : i.samples_without_imu) s.add("samples without imu: " + kv.first, kv.second);
  s.add("imu silent for (s)", silent);
  s.add("imu max gap (s)", config_.node.imu_max_gap);
  if (!i.last_problem.empty()) s.add("last imu problem", i.last_problem);
}

}  // namespace pc_ekf
