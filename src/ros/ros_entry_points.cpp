#include "pc_ekf/ros/ros_entry_points.h"

#include "pc_ekf/ros/model_plugins.h"

namespace {

pc_ekf::BagRecord readBagWithOptions(const std::string& path, const pc_ekf::BagReadOptions& options) {
  return pc_ekf::readBag(path, options);
}

}  // namespace

extern "C" const pc_ekf::RosEntryPoints* pc_ekf_ros_entry_points() {
  static const pc_ekf::RosEntryPoints entry{&readBagWithOptions, &pc_ekf::bagReadOptions,
                                            &pc_ekf::modelRegistryWithPlugins,
                                            &pc_ekf::bagRecordStream};
  return &entry;
}
