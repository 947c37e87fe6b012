// The "imu" and "odom" statuses of estimator_node (issue 29; odom: the
// forward speed): kept apart from estimator_diagnostics.cpp's other statuses.
#include <diagnostic_msgs/DiagnosticStatus.h>

#include <numeric>
#include <sstream>

#include "pc_ekf/ros/estimator_diagnostics.h"

namespace pc_ekf {

void EstimatorDiagnostics::reportImu(diagnostic_updater::DiagnosticStatusWrapper& s) {
  reportAligned(s, imu_, imu_now_, "imu", "imu/data", imu_reported_at_, imu_reported_received_);
}

void EstimatorDiagnostics::reportOdom(diagnostic_updater::DiagnosticStatusWrapper& s) {
  reportAligned(s, odom_, odom_now_, "odom", "odom", odom_reported_at_, odom_reported_received_);
}

void EstimatorDiagnostics::reportAligned(diagnostic_updater::DiagnosticStatusWrapper& s,
                                         const ImuInputStats& i, double stats_now, const char* name,
                                         const char* topic, ros::WallTime& reported_at,
                                         std::uint64_t& reported_received) {
  const std::string n = name;
  const bool imu = n == "imu";
  const auto total = [](const std::map<std::string, std::uint64_t>& m) {
    std::uint64_t sum = 0;
    for (const auto& kv : m) sum += kv.second;
    return sum;
  };
  const ros::WallTime now = ros::WallTime::now();
  const double elapsed = (now - reported_at).toSec();
  const double received_rate =
      reported_at.isZero() || elapsed <= 0.0
          ? 0.0
          : static_cast<double>(i.received - reported_received) / elapsed;
  reported_at = now;
  reported_received = i.received;
  const double silent = i.last_message_wall > 0.0 ? stats_now - i.last_message_wall : -1.0;

  std::ostringstream m;
  unsigned char level = diagnostic_msgs::DiagnosticStatus::OK;
  if (i.received == 0) {
    level = diagnostic_msgs::DiagnosticStatus::WARN;
    m << "no " << topic << " message yet";
  } else if (silent > config_.node.road_wait_timeout) {
    level = diagnostic_msgs::DiagnosticStatus::WARN;
    m << topic << " silent for " << silent << " s";
  } else {
    m << i.samples_aligned << " samples aligned, " << (imu ? "IMU" : "odom") << " at " << i.rate << " Hz";
  }
  const std::uint64_t without = total(i.samples_without_imu);
  if (without > 0) {
    m << "; " << without << " samples without " << (imu ? "IMU channels" : "the speed");
    level = std::max<unsigned char>(level, diagnostic_msgs::DiagnosticStatus::WARN);
  }
  s.summary(level, m.str());
  s.add(n + " rate (Hz, from stamps)", i.rate);
  s.add(n + " messages/s received", received_rate);
  s.add(n + " rate changes", i.rate_changes);
  s.add(n + " messages received", i.received);
  s.add(n + " messages used", i.used);
  for (const auto& kv : i.rejected) s.add(n + " rejected: " + kv.first, kv.second);
  for (const auto& kv : i.problems) s.add(n + " problems: " + kv.first, kv.second);
  s.add("stamp offset (ms, sample - nearest " + n + ")", 1e3 * i.last_offset);
  s.add("max |stamp offset| (ms)", 1e3 * i.max_abs_offset);
  s.add("samples waiting for " + n, i.waiting);
  s.add("max samples waiting for " + n, i.max_waiting);
  s.add("samples aligned", i.samples_aligned);
  s.add("samples without " + n, without);
  for (const auto& kv : i.samples_without_imu) s.add("samples without " + n + ": " + kv.first, kv.second);
  s.add(n + " silent for (s)", silent);
  s.add(n + " max gap (s)", config_.node.imu_max_gap);
  if (!i.last_problem.empty()) s.add("last " + n + " problem", i.last_problem);
}

}  // namespace pc_ekf
