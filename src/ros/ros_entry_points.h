// The ROS layer's functions that the offline tools reach through dlopen
// (pc_ekf/tools/ros_on_demand.h) instead of linking: a tool that reads no bag
// and uses no plugin model then starts without ROS's shared libraries.
#pragma once

#include <memory>
#include <string>

#include "pc_ekf/model/model_type.h"
#include "pc_ekf/ros/bag_io.h"
#include "pc_ekf/ros/bag_stream.h"

namespace pc_ekf {

struct RosEntryPoints {
  BagRecord (*read_bag)(const std::string& path, const BagReadOptions& options);
  BagReadOptions (*bag_read_options)(const EstimatorConfig& config);
  ModelRegistry (*model_registry_with_plugins)();
  std::unique_ptr<RecordStream> (*bag_record_stream)(const std::string& path,
                                                     const BagReadOptions& options);
};

constexpr const char* kRosLibrary = "libpc_ekf_ros.so";
constexpr const char* kRosEntryPointsSymbol = "pc_ekf_ros_entry_points";

}  // namespace pc_ekf

// Defined in libpc_ekf_ros (dlsym kRosEntryPointsSymbol).
extern "C" const pc_ekf::RosEntryPoints* pc_ekf_ros_entry_points();
