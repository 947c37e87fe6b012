// estimator_node: the online PC-EKF parameter estimator (see EstimatorRos).
#include <ros/callback_queue.h>
#include <ros/ros.h>

#include <csignal>
#include <exception>
#include <memory>

#include "pc_ekf/ros/estimator_ros.h"

namespace {

volatile std::sig_atomic_t g_stop = 0;

void requestStop(int) { g_stop = 1; }

}  // namespace

int main(int argc, char** argv) {
  // Own SIGINT/SIGTERM handling: the estimator (and its shutdown checkpoint,
  // docs/reliability.md "Checkpoints") is destroyed before ros::shutdown, while logging works.
  ros::init(argc, argv, "estimator_node", ros::init_options::NoSigintHandler);
  std::signal(SIGINT, requestStop);
  std::signal(SIGTERM, requestStop);
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  std::unique_ptr<pc_ekf::EstimatorRos> estimator;
  try {
    estimator = std::make_unique<pc_ekf::EstimatorRos>(nh, pnh, ros::this_node::getName());
  } catch (const pc_ekf::ConfigError& e) {
    ROS_FATAL("%s: invalid configuration: %s", ros::this_node::getName().c_str(), e.what());
    return 2;
  } catch (const pc_ekf::CheckpointError& e) {
    ROS_FATAL("%s: cannot resume: %s", ros::this_node::getName().c_str(), e.what());
    return 2;
  } catch (const std::exception& e) {  // e.g. an unreadable road file
    ROS_FATAL("%s: cannot start: %s", ros::this_node::getName().c_str(), e.what());
    return 1;
  }
  // ros::spin() on this thread, stopping on a signal as well.
  while (ros::ok() && !g_stop) {
    ros::getGlobalCallbackQueue()->callAvailable(ros::WallDuration(0.1));
  }
  estimator.reset();
  ros::shutdown();
  return 0;
}
