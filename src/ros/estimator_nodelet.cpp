// pc_ekf/EstimatorNodelet: estimator_node's class (EstimatorRos) in a
// nodelet manager. Its callbacks use the nodelet's single-threaded queue.
#include <nodelet/nodelet.h>

#include <memory>
#include <pluginlib/class_list_macros.hpp>

#include "pc_ekf/ros/estimator_ros.h"

namespace pc_ekf {

class EstimatorNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      estimator_ =
          std::make_unique<EstimatorRos>(getNodeHandle(), getPrivateNodeHandle(), getName());
    } catch (const ConfigError& e) {
      NODELET_FATAL("invalid configuration: %s", e.what());
      throw;  // the manager reports the failed load
    } catch (const CheckpointError& e) {
      NODELET_FATAL("cannot resume: %s", e.what());
      throw;
    }
  }

  std::unique_ptr<EstimatorRos> estimator_;
};

}  // namespace pc_ekf

PLUGINLIB_EXPORT_CLASS(pc_ekf::EstimatorNodelet, nodelet::Nodelet)
