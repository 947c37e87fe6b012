// replay_node: plays a bag's topics into the graph, in the node's namespace
// (rosrun pc_ekf replay_node _bag:=FILE.bag). Parameters: src/ros/replay_options.h
// and docs/nodes.md "replay_node". Exit 0 when done, 2 on a bad bag or parameter.
#include <ros/ros.h>

#include <memory>

#include "pc_ekf/ros/replay_bag.h"
#include "pc_ekf/ros/replay_options.h"
#include "pc_ekf/ros/replay_player.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "replay_node");
  ros::NodeHandle nh;
  ros::NodeHandle private_nh("~");

  pc_ekf::ReplayOptions options;
  std::unique_ptr<pc_ekf::ReplayBag> bag;
  std::unique_ptr<pc_ekf::BagReplayer> replayer;
  try {
    options = pc_ekf::loadReplayOptions(private_nh);
    bag = std::make_unique<pc_ekf::ReplayBag>(options.bag);
    replayer = std::make_unique<pc_ekf::BagReplayer>(nh, *bag, options);
  } catch (const std::exception& e) {
    ROS_FATAL("replay_node: %s", e.what());
    return 2;
  }

  // The handshake's estimates arrive while the main thread plays.
  ros::AsyncSpinner spinner(1);
  spinner.start();
  ROS_INFO("replay_node: %zu messages on %zu topics, %.3f s of bag time, from %s",
           bag->messageCount(), bag->topics().size(), (bag->endTime() - bag->beginTime()).toSec(),
           options.bag.c_str());

  replayer->waitForSubscribers();
  if (options.start_delay > 0.0) ros::WallDuration(options.start_delay).sleep();
  try {
    while (ros::ok() && replayer->playOnce() && options.loop) {
      ROS_INFO("replay_node: %s; looping", replayer->summary().c_str());
    }
    if (ros::ok()) replayer->finish();
  } catch (const std::exception& e) {
    ROS_FATAL("replay_node: %s: %s", options.bag.c_str(), e.what());
    return 1;
  }
  ROS_INFO("replay_node: %s", replayer->summary().c_str());
  // Publishing only queues; stay connected so the last messages get written.
  if (ros::ok() && options.linger > 0.0) ros::WallDuration(options.linger).sleep();
  spinner.stop();
  return 0;
}
