// estimator_node: the online PC-EKF parameter estimator (see EstimatorRos).
#include <ros/ros.h>

#include <exception>
#include <memory>

#include "ros/estimator_ros.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "estimator_node");
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  std::unique_ptr<pc_ekf::EstimatorRos> estimator;
  try {
    estimator = std::make_unique<pc_ekf::EstimatorRos>(nh, pnh, ros::this_node::getName());
  } catch (const pc_ekf::ConfigError& e) {
    ROS_FATAL("%s: invalid configuration: %s", ros::this_node::getName().c_str(), e.what());
    return 2;
  } catch (const std::exception& e) {  // e.g. an unreadable road file
    ROS_FATAL("%s: cannot start: %s", ros::this_node::getName().c_str(), e.what());
    return 1;
  }
  ros::spin();
  return 0;
}
