// The "load and clock" status: load changes found (filter.reopen.mode load),
// the clock offset between the IMU and the suspension (filter.horizon) and
// the stops recognised (measurement.standstill).
#include <cmath>
#include <sstream>

#include "pc_ekf/ros/estimator_diagnostics.h"

namespace pc_ekf {

void EstimatorDiagnostics::reportLoad(diagnostic_updater::DiagnosticStatusWrapper& s) {
  using diagnostic_msgs::DiagnosticStatus;
  const LastUpdate& u = last_;
  const bool fresh = u.load_changes != reported_load_changes_ && u.load_changes > 0;
  reported_load_changes_ = u.load_changes;
  std::ostringstream m;
  m << u.load_changes << " load change" << (u.load_changes == 1 ? "" : "s") << " found";
  if (u.load_changes > 0) {
    m << "; the last began at t = " << u.load_change_time << " s (found at t = " << u.load_found_at
      << " s)";
  }
  if (std::isfinite(u.clock_offset)) {
    m << "; clock offset " << 1e3 * u.clock_offset << " +- " << 1e3 * u.clock_offset_std << " ms";
  }
  if (u.standing) m << "; standing still";
  // A new change is news for whoever watches (WARN once), not a fault.
  s.summary(fresh ? DiagnosticStatus::WARN : DiagnosticStatus::OK, m.str());
  s.add("load changes", u.load_changes);
  s.add("last load change began at (s)", u.load_change_time);
  s.add("last load change found at (s)", u.load_found_at);
  for (const std::string& line : u.load_summary) s.add("load after it", line);
  s.add("clock offset (ms, IMU stamps behind the suspension's)", 1e3 * u.clock_offset);
  s.add("clock offset std (ms)", 1e3 * u.clock_offset_std);
  s.add("standing still", u.standing ? "yes" : "no");
  s.add("stops recognised", u.stops);
  s.add("samples standing", u.standing_samples);
}

}  // namespace pc_ekf
