// replay_node's playback: one publisher per recorded topic (the recorded
// type, generic through rosbag::MessageInstance, so any bag replays), topic
// names made relative so they land in the node's namespace, recorded timing
// scaled by ~rate on the wall clock, optional /clock and lossless handshake.
#pragma once

#include <ros/node_handle.h>
#include <ros/publisher.h>

#include <map>
#include <memory>
#include <string>

#include "pc_ekf/ros/replay_bag.h"
#include "pc_ekf/ros/replay_handshake.h"
#include "pc_ekf/ros/replay_options.h"

namespace pc_ekf {

struct ReplayCounts {
  std::map<std::string, std::size_t> per_topic;  // by relative topic
  std::size_t passes = 0;
  double wall_seconds = 0.0;
};

class BagReplayer {
 public:
  // Advertises everything; `nh` is the node's (public) handle.
  BagReplayer(ros::NodeHandle& nh, ReplayBag& bag, const ReplayOptions& options);

  // The ~wait_for_subscribers wait. False when ROS shut down or
  // ~wait_timeout passed (then it warns and playing may still go on).
  bool waitForSubscribers();
  // Plays the bag once. False when ROS shut down on the way.
  bool playOnce();
  // After the last pass: waits for the answer to the last sample (lossless).
  void finish();

  const ReplayCounts& counts() const { return counts_; }
  // One line: messages per topic, passes, wall time, handshake results.
  std::string summary() const;

 private:
  // Subscribers the master knows for `topic`, other than this node.
  bool allKnownSubscribersConnected(std::string* missing) const;

  ros::NodeHandle& nh_;
  ReplayBag& bag_;
  ReplayOptions options_;
  std::map<std::string, ros::Publisher> publishers_;  // by recorded topic
  ros::Publisher clock_;
  std::string lossless_topic_;  // recorded topic gated by the handshake ("" = none)
  // imu/data in the bag (issue 29): with the handshake, a sample is answered
  // only once an IMU message stamped at or after it arrived, so the IMU
  // messages up to that one are published ahead before waiting.
  std::string imu_topic_;
  std::unique_ptr<EstimateHandshake> handshake_;
  ReplayCounts counts_;
};

}  // namespace pc_ekf
