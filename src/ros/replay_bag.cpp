#include "pc_ekf/ros/replay_bag.h"

#include <ros/serialization.h>
#include <rosbag/view.h>

#include <filesystem>
#include <sstream>

#include "pc_ekf/ros/bag_check.h"

namespace pc_ekf {

ReplayBag::ReplayBag(const std::string& path) : path_(path), bag_(new rosbag::Bag) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw BagError(path + ": no such bag file");
  // rosbag trusts the lengths and offsets in the file (bag_check.h).
  const std::string problem = bagStructureProblem(path);
  if (!problem.empty()) throw BagError(path + ": corrupt, truncated or unsupported bag: " + problem);
  try {
    bag_->open(path, rosbag::bagmode::Read);
  } catch (const std::exception& e) {
    throw BagError(path +
                   ": cannot open as a ROS bag (unreadable, truncated or not a bag): " + e.what());
  }
  try {
    rosbag::View everything(*bag_);
    for (const rosbag::ConnectionInfo* c : everything.getConnections()) {
      ReplayTopic& t = topics_[c->topic];
      if (!t.datatype.empty() && (t.datatype != c->datatype || t.md5sum != c->md5sum)) {
        throw BagError(path + ": topic '" + c->topic + "' was recorded with two types (" +
                       t.datatype + ", " + c->datatype + "); one publisher cannot replay both");
      }
      t.bag_topic = c->topic;
      t.topic = relativeTopic(c->topic);
      t.datatype = c->datatype;
      t.md5sum = c->md5sum;
      t.definition = c->msg_def;
      t.has_header = definitionStartsWithHeader(c->msg_def);
      if (c->header) {
        const auto latching = c->header->find("latching");
        t.latching = t.latching || (latching != c->header->end() && latching->second == "1");
      }
    }
    for (auto& [name, topic] : topics_) {
      topic.messages = rosbag::View(*bag_, rosbag::TopicQuery(name)).size();
      messages_ += topic.messages;
    }
    begin_ = everything.getBeginTime();
    end_ = everything.getEndTime();
  } catch (const BagError&) {
    throw;
  } catch (const std::exception& e) {
    throw BagError(path + ": corrupt bag: " + e.what());
  }
  if (messages_ == 0) throw BagError(path + ": the bag holds no messages");
  for (const auto& [name, topic] : topics_) {
    if (topic.topic.empty()) throw BagError(path + ": a topic has an empty name");
  }
}

std::optional<std::string> ReplayBag::findTopic(const std::string& suffix) const {
  for (const auto& [name, topic] : topics_) {
    if (topicMatches(name, suffix)) return name;
  }
  return std::nullopt;
}

std::string relativeTopic(const std::string& topic) {
  const auto first = topic.find_first_not_of('/');
  return first == std::string::npos ? std::string() : topic.substr(first);
}

bool definitionStartsWithHeader(const std::string& definition) {
  std::istringstream lines(definition);
  for (std::string line; std::getline(lines, line);) {
    std::istringstream words(line.substr(0, line.find('#')));
    std::string type, name;
    if (!(words >> type)) continue;  // blank or comment
    words >> name;
    return (type == "Header" || type == "std_msgs/Header") && name == "header";
  }
  return false;
}

ros::Time headerStamp(const rosbag::MessageInstance& message) {
  // Serialized Header: uint32 seq, uint32 sec, uint32 nsec, string frame_id.
  std::vector<std::uint8_t> buffer(message.size());
  if (buffer.size() < 12) {
    throw BagError("a message on '" + message.getTopic() + "' is too short to hold a header");
  }
  ros::serialization::OStream out(buffer.data(), static_cast<std::uint32_t>(buffer.size()));
  message.write(out);
  ros::serialization::IStream in(buffer.data(), static_cast<std::uint32_t>(buffer.size()));
  std::uint32_t seq = 0;
  ros::Time stamp;
  in >> seq >> stamp.sec >> stamp.nsec;
  return stamp;
}

}  // namespace pc_ekf
