// The ROS layer for estimate_offline and calibrate_vehicle, loaded when first
// needed (reading a bag, a plugin model): a run on a CSV or synthetic record
// with a built-in model starts without ROS's ~40 shared libraries (18 -> 4 ms
// for `estimate_offline --help`). libpc_ekf_ros.so is found as a linked
// library would be (the executable's run path, LD_LIBRARY_PATH).
#pragma once

#include <dlfcn.h>

#include <memory>
#include <stdexcept>
#include <string>

#include "pc_ekf/ros/ros_entry_points.h"

namespace pc_ekf {

// Loaded once (thread-safe), kept loaded; std::runtime_error naming the
// library and the loader's reason when it cannot be.
inline const RosEntryPoints& rosOnDemand(const std::string& why) {
  static const RosEntryPoints* const entry = [&why]() -> const RosEntryPoints* {
    void* library = dlopen(kRosLibrary, RTLD_NOW | RTLD_GLOBAL);
    if (!library) {
      const char* reason = dlerror();
      throw std::runtime_error(std::string("cannot load ") + kRosLibrary + " (" + why +
                               "): " + (reason ? reason : "unknown reason"));
    }
    using Get = const RosEntryPoints* (*)();
    const auto get = reinterpret_cast<Get>(dlsym(library, kRosEntryPointsSymbol));
    if (!get) {
      throw std::runtime_error(std::string(kRosLibrary) + " has no " + kRosEntryPointsSymbol +
                               " (a library of another pc_ekf version?)");
    }
    return get();
  }();
  return *entry;
}

inline BagRecord readBagOnDemand(const std::string& path, const EstimatorConfig& config) {
  const RosEntryPoints& ros = rosOnDemand("needed to read the bag " + path);
  return ros.read_bag(path, ros.bag_read_options(config));
}

// A road-free bag read as a stream (bag_stream.h).
inline std::unique_ptr<RecordStream> bagRecordStreamOnDemand(const std::string& path,
                                                             const EstimatorConfig& config) {
  const RosEntryPoints& ros = rosOnDemand("needed to read the bag " + path);
  return ros.bag_record_stream(path, ros.bag_read_options(config));
}

// The built-in model types now; a plugin name (package/Class) loads the ROS
// layer and asks its registry (pluginlib), with its errors.
inline ModelRegistry modelRegistryOnDemand() {
  ModelRegistry registry;
  registry.addResolver([](const std::string& name) -> std::shared_ptr<const ModelType> {
    if (name.find('/') == std::string::npos) return nullptr;  // plugins are package/Class
    static const ModelRegistry plugins =
        rosOnDemand("needed for the model plugin " + name).model_registry_with_plugins();
    return plugins.find(name);
  });
  return registry;
}

}  // namespace pc_ekf
