// estimator_node's counters and stamps in a checkpoint (io/checkpoint.h is
// ROS-free: stamps as sec/nsec, counters as a name -> count map).
#pragma once

#include <ros/time.h>

#include <cstdint>
#include <map>
#include <string>

#include "pc_ekf/io/checkpoint.h"
#include "pc_ekf/ros/estimator_diagnostics.h"

namespace pc_ekf {

inline CheckpointStamp checkpointStamp(const ros::Time& t) { return {t.sec, t.nsec}; }
inline ros::Time rosTime(const CheckpointStamp& s) { return ros::Time(s.sec, s.nsec); }

// Names as in EstimatorCounters; the per-reason maps as "<map>.<reason>".
std::map<std::string, std::uint64_t> counterMap(const EstimatorCounters& c);
// Throws CheckpointError naming `path` and the unknown counter.
EstimatorCounters countersFromMap(const std::map<std::string, std::uint64_t>& m,
                                  const std::string& path);

}  // namespace pc_ekf
