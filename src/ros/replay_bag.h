// The bag side of replay_node: opens and checks a bag, describes its topics
// (type, definition, message count) and reads header stamps of messages of
// any type whose definition starts with a std_msgs/Header.
#pragma once

#include <ros/time.h>
#include <rosbag/bag.h>
#include <rosbag/message_instance.h>

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "pc_ekf/ros/bag_io.h"  // BagError

namespace pc_ekf {

struct ReplayTopic {
  std::string bag_topic;  // as recorded, e.g. "/road/profile"
  std::string topic;      // relative (no leading '/'): lands in the node's namespace
  std::string datatype, md5sum, definition;
  bool latching = false;
  bool has_header = false;  // definition starts with a std_msgs/Header field
  std::size_t messages = 0;
};

class ReplayBag {
 public:
  // Opens `path` read-only and indexes its topics. Throws BagError naming the
  // file for a missing, unreadable or corrupt bag, a bag without messages and
  // a topic recorded with two different message types.
  explicit ReplayBag(const std::string& path);

  const std::string& path() const { return path_; }
  rosbag::Bag& bag() { return *bag_; }
  // By recorded topic name, sorted.
  const std::map<std::string, ReplayTopic>& topics() const { return topics_; }
  std::size_t messageCount() const { return messages_; }
  ros::Time beginTime() const { return begin_; }
  ros::Time endTime() const { return end_; }

  // The recorded topic matching `suffix` (bag_io's topicMatches), or none.
  std::optional<std::string> findTopic(const std::string& suffix) const;

 private:
  std::string path_;
  std::unique_ptr<rosbag::Bag> bag_;
  std::map<std::string, ReplayTopic> topics_;
  std::size_t messages_ = 0;
  ros::Time begin_, end_;
};

// "some/topic" for "/some/topic" (names in a bag are usually absolute).
std::string relativeTopic(const std::string& topic);

// True when the first field of a message definition is a std_msgs/Header.
bool definitionStartsWithHeader(const std::string& definition);

// header.stamp of a message whose type starts with a Header (check with
// definitionStartsWithHeader first). Throws BagError when it is too short.
ros::Time headerStamp(const rosbag::MessageInstance& message);

}  // namespace pc_ekf
