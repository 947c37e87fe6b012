// main() of a rostest's gtest node: gtest and ROS initialised, callbacks on
// two spinner threads while the tests run.
#pragma once

#include <gtest/gtest.h>
#include <ros/ros.h>

namespace pc_ekf::test {

inline int runRostests(int argc, char** argv, const char* tester_name) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, tester_name);
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  spinner.stop();
  ros::shutdown();
  return result;
}

}  // namespace pc_ekf::test
