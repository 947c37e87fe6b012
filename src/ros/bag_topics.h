// Reading a bag's topics, shared by readBag (bag_io.cpp) and the road-free
// stream (bag_stream.cpp) so that both read and merge samples alike.
#pragma once

#include <ros/message_traits.h>
#include <ros/serialization.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>

#include <algorithm>
#include <cstdint>
#include <functional>
#include <set>
#include <string>
#include <vector>

#include "pc_ekf/filter/measurement.h"
#include "pc_ekf/ros/bag_check.h"
#include "pc_ekf/ros/bag_io.h"

namespace pc_ekf {
namespace bag_topics {

std::int64_t nanoseconds(const ros::Time& t);
std::string stampText(const ros::Time& t);
std::string join(const std::vector<std::string>& items);

// The one topic of the bag that matches `suffix` with type T, or "" when
// none matches. Throws BagError when several match or the type differs; a
// topic recorded with another definition of T is an error too, unless
// `other_definition` is given: then it is skipped and named there.
template <typename T>
std::string findTopic(const std::string& path, rosbag::Bag& bag, const std::string& suffix,
                      std::vector<std::string>* all_topics,
                      std::string* other_definition = nullptr) {
  rosbag::View everything(bag);
  std::set<std::string> matches;
  all_topics->clear();
  const std::string expected = ros::message_traits::DataType<T>::value();
  for (const rosbag::ConnectionInfo* c : everything.getConnections()) {
    all_topics->push_back(c->topic + " (" + c->datatype + ")");
    if (!topicMatches(c->topic, suffix)) continue;
    if (c->datatype != expected) {
      throw BagError(path + ": topic '" + c->topic + "' has type " + c->datatype + ", expected " +
                     expected);
    }
    if (c->md5sum != "*" && c->md5sum != ros::message_traits::MD5Sum<T>::value()) {
      if (other_definition) {
        *other_definition = c->topic;
        continue;
      }
      throw BagError(path + ": topic '" + c->topic +
                     "' was recorded with a different definition of " + expected + " (md5 " +
                     c->md5sum + ")");
    }
    matches.insert(c->topic);
  }
  std::sort(all_topics->begin(), all_topics->end());
  all_topics->erase(std::unique(all_topics->begin(), all_topics->end()), all_topics->end());
  if (matches.size() > 1) {
    throw BagError(path + ": several topics end in '" + suffix +
                   "': " + join(std::vector<std::string>(matches.begin(), matches.end())));
  }
  return matches.empty() ? std::string() : *matches.begin();
}

// Message `m` (the `index`th read on its topic, from 0) decoded into `msg`
// through `bytes` (scratch). Throws BagError when it cannot be.
template <typename T>
void decodeMessage(const std::string& path, const rosbag::MessageInstance& m, std::size_t index,
                   std::vector<std::uint8_t>& bytes, T* msg) {
  // roscpp resizes a vector to the length stored in the message before it
  // checks the bytes are there: check the lengths first (bag_check.h).
  bytes.resize(m.size());
  ros::serialization::OStream raw(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
  m.write(raw);
  const std::string problem =
      serializedMessageProblem(ros::message_traits::Definition<T>::value(),
                               ros::message_traits::DataType<T>::value(), bytes.data(), bytes.size());
  if (!problem.empty()) {
    throw BagError(path + ": message " + std::to_string(index + 1) + " on '" + m.getTopic() +
                   "' cannot be decoded: " + problem);
  }
  *msg = T();
  ros::serialization::IStream in(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
  ros::serialization::deserialize(in, *msg);
}

// Every message on `topic` to `take`, in bag order, decoded one at a time: a
// long bag's messages are never held (their objects are many times the
// numbers they carry).
template <typename T>
void readTopic(const std::string& path, rosbag::Bag& bag, const std::string& topic,
               const std::function<void(const T&)>& take) {
  if (topic.empty()) return;
  rosbag::View view(bag, rosbag::TopicQuery(topic));
  std::vector<std::uint8_t> bytes;
  std::size_t read = 0;
  T msg;
  for (const rosbag::MessageInstance& m : view) {
    decodeMessage(path, m, read++, bytes, &msg);
    take(msg);
  }
}

struct StampedSample {
  std::int64_t ns = 0;
  ros::Time stamp;
  Measurement m;
};

// The samples [begin, end), all of one stamp, as one sample (channels
// ascending; moved when alone and in order). Throws BagError when two
// observe the same channel.
Measurement mergeStampGroup(const std::string& path, StampedSample* begin, StampedSample* end,
                            int channels);

}  // namespace bag_topics
}  // namespace pc_ekf
