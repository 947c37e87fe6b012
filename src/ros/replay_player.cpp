#include "pc_ekf/ros/replay_player.h"

#include <optional>
#include <vector>

#include <ros/console.h>
#include <ros/master.h>
#include <ros/this_node.h>
#include <rosbag/view.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/Imu.h>

#include <algorithm>
#include <iomanip>
#include <sstream>

namespace pc_ekf {

namespace {

// A subscriber the master lists but that never connects (a node killed
// without unregistering) must not stall the start for ever.
constexpr double kKnownSubscriberPatience = 5.0;  // s

// Sleeps until `target` in slices, so that a shutdown is noticed. False
// when ROS shut down.
bool sleepUntil(const ros::WallTime& target) {
  for (ros::WallTime now = ros::WallTime::now(); now < target; now = ros::WallTime::now()) {
    if (!ros::ok()) return false;
    std::min(target - now, ros::WallDuration(0.05)).sleep();
  }
  return ros::ok();
}

}  // namespace

BagReplayer::BagReplayer(ros::NodeHandle& nh, ReplayBag& bag, const ReplayOptions& options)
    : nh_(nh), bag_(bag), options_(options) {
  for (const auto& [name, topic] : bag_.topics()) {
    const int queue_size =
        options_.queue_size > 0 ? options_.queue_size : static_cast<int>(topic.messages) + 1;
    ros::AdvertiseOptions advertise(topic.topic, static_cast<std::uint32_t>(queue_size),
                                    topic.md5sum, topic.datatype, topic.definition);
    advertise.latch = topic.latching;
    publishers_[name] = nh_.advertise(advertise);
    counts_.per_topic[topic.topic] = 0;
  }
  if (options_.publish_clock) clock_ = nh_.advertise<rosgraph_msgs::Clock>("/clock", 100);
  if (options_.lossless) {
    const auto gated = bag_.findTopic(options_.lossless_topic);
    if (!gated) {
      throw BagError(bag_.path() + ": ~lossless is true but no topic ends in '" +
                     options_.lossless_topic + "' (~lossless_topic)");
    }
    if (!bag_.topics().at(*gated).has_header) {
      throw BagError(bag_.path() + ": ~lossless needs header stamps, but the type of '" + *gated +
                     "' (" + bag_.topics().at(*gated).datatype + ") has no std_msgs/Header");
    }
    lossless_topic_ = *gated;
    if (const auto imu = bag_.findTopic(kImuTopic)) imu_topic_ = *imu;
    handshake_ = std::make_unique<EstimateHandshake>(nh_, options_.estimate_topic);
  }
}

bool BagReplayer::allKnownSubscribersConnected(std::string* missing) const {
  XmlRpc::XmlRpcValue args, result, payload;
  args[0] = ros::this_node::getName();
  if (!ros::master::execute("getSystemState", args, result, payload, false)) return true;
  std::map<std::string, int> known;  // resolved topic -> subscriber nodes other than us
  const XmlRpc::XmlRpcValue& subscribers = payload[1];
  for (int i = 0; i < subscribers.size(); ++i) {
    const XmlRpc::XmlRpcValue& nodes = subscribers[i][1];
    int count = 0;
    for (int j = 0; j < nodes.size(); ++j) {
      count += static_cast<std::string>(nodes[j]) != ros::this_node::getName();
    }
    known[static_cast<std::string>(subscribers[i][0])] = count;
  }
  for (const auto& [name, publisher] : publishers_) {
    const auto k = known.find(publisher.getTopic());
    if (k != known.end() && static_cast<int>(publisher.getNumSubscribers()) < k->second) {
      *missing = publisher.getTopic() + " (" + std::to_string(publisher.getNumSubscribers()) +
                 " of " + std::to_string(k->second) + " subscribers connected)";
      return false;
    }
  }
  return true;
}

bool BagReplayer::waitForSubscribers() {
  if (!options_.wait_for_subscribers) return true;
  std::vector<const ros::Publisher*> required;
  for (const std::string& suffix : options_.subscriber_topics) {
    const auto topic = bag_.findTopic(suffix);
    if (topic) {
      required.push_back(&publishers_.at(*topic));
    } else {
      ROS_WARN("replay_node: ~subscriber_topics: no topic in %s ends in '%s'; not waiting for it",
               bag_.path().c_str(), suffix.c_str());
    }
  }
  const ros::WallTime start = ros::WallTime::now();
  ros::WallTime last_report = start;
  while (ros::ok()) {
    std::string missing;
    for (const ros::Publisher* p : required) {
      if (static_cast<int>(p->getNumSubscribers()) < options_.min_subscribers) {
        missing = p->getTopic() + " (" + std::to_string(p->getNumSubscribers()) + " of " +
                  std::to_string(options_.min_subscribers) + " subscribers)";
        break;
      }
    }
    if (missing.empty() && handshake_ && !handshake_->connected()) {
      missing = handshake_->topic() + " (no estimator publishing it yet; ~lossless)";
    }
    const double waited = (ros::WallTime::now() - start).toSec();
    std::string unconnected;
    if (missing.empty() && !allKnownSubscribersConnected(&unconnected)) {
      if (waited < kKnownSubscriberPatience) {
        missing = unconnected;
      } else {
        ROS_WARN("replay_node: %s; starting anyway", unconnected.c_str());
      }
    }
    if (missing.empty()) return true;
    if (options_.wait_timeout > 0.0 && waited >= options_.wait_timeout) {
      ROS_WARN("replay_node: still waiting for %s after %.1f s (~wait_timeout); starting anyway",
               missing.c_str(), waited);
      return false;
    }
    if ((ros::WallTime::now() - last_report).toSec() >= 5.0) {
      ROS_INFO("replay_node: waiting for %s", missing.c_str());
      last_report = ros::WallTime::now();
    }
    ros::WallDuration(0.02).sleep();
  }
  return false;
}

bool BagReplayer::playOnce() {
  rosbag::View view(bag_.bag());
  const std::size_t total = view.size();
  const ros::Time first = bag_.beginTime();
  const double span = (bag_.endTime() - first).toSec();
  const ros::WallTime start = ros::WallTime::now();
  std::size_t index = 0;
  int next_progress = 25;
  // IMU messages published ahead of their place (imu_topic_ with the
  // handshake). Read into memory first: two views reading one bag at once
  // are not safe.
  std::vector<sensor_msgs::Imu::ConstPtr> imu_msgs;
  if (handshake_ && !imu_topic_.empty()) {
    rosbag::View imu_view(bag_.bag(), rosbag::TopicQuery(imu_topic_));
    for (const rosbag::MessageInstance& imu : imu_view) {
      const auto msg = imu.instantiate<sensor_msgs::Imu>();
      if (!msg) {  // another definition: no look-ahead
        imu_msgs.clear();
        break;
      }
      imu_msgs.push_back(msg);
    }
  }
  const bool look_ahead = !imu_msgs.empty();
  std::size_t imu_ahead = 0, imu_seen = 0;
  std::optional<ros::Time> imu_last;
  const auto publishNextImu = [&] {
    const sensor_msgs::Imu& imu = *imu_msgs[imu_ahead];
    if (!imu_last || *imu_last < imu.header.stamp) imu_last = imu.header.stamp;
    publishers_.at(imu_topic_).publish(imu);
    ++counts_.per_topic[bag_.topics().at(imu_topic_).topic];
    ++imu_ahead;
  };
  const auto publishImuThrough = [&](const ros::Time& stamp) {
    while ((!imu_last || *imu_last < stamp) && imu_ahead < imu_msgs.size()) publishNextImu();
  };
  std::optional<ros::Time> awaited;  // the sample whose answer the next wait is for
  for (const rosbag::MessageInstance& m : view) {
    if (!ros::ok()) return false;
    if (options_.rate > 0.0 &&
        !sleepUntil(start + ros::WallDuration((m.getTime() - first).toSec() / options_.rate))) {
      return false;
    }
    if (clock_) {
      rosgraph_msgs::Clock clock;
      clock.clock = m.getTime();
      clock_.publish(clock);
    }
    if (look_ahead && m.getTopic() == imu_topic_) {
      // Published ahead already, or now in its place.
      if (++imu_seen > imu_ahead && imu_ahead < imu_msgs.size()) publishNextImu();
      ++index;
      continue;
    }
    if (handshake_ && m.getTopic() == lossless_topic_) {
      if (awaited) publishImuThrough(*awaited);
      handshake_->waitForAnswer(options_.lossless_timeout);  // the previous sample's
      awaited = headerStamp(m);
      handshake_->expect(*awaited);
    }
    publishers_.at(m.getTopic()).publish(m);
    ++counts_.per_topic[bag_.topics().at(m.getTopic()).topic];
    ++index;
    if (static_cast<int>(100 * index / total) >= next_progress) {
      ROS_INFO("replay_node: %d %% (bag time %.3f of %.3f s)", next_progress,
               (m.getTime() - first).toSec(), span);
      next_progress += 25;
    }
  }
  if (awaited) publishImuThrough(*awaited);  // before finish() waits for the last answer
  ++counts_.passes;
  counts_.wall_seconds += (ros::WallTime::now() - start).toSec();
  return true;
}

void BagReplayer::finish() {
  if (handshake_) handshake_->waitForAnswer(options_.lossless_timeout);
}

std::string BagReplayer::summary() const {
  std::ostringstream o;
  o << "replayed " << bag_.path() << ":";
  const char* separator = " ";
  for (const auto& [topic, count] : counts_.per_topic) {
    o << separator << count << " on " << topic;
    separator = ", ";
  }
  o << std::fixed << std::setprecision(3) << " (" << counts_.passes << " pass"
    << (counts_.passes == 1 ? "" : "es") << ", " << counts_.wall_seconds << " s wall, rate "
    << options_.rate << (options_.rate == 0.0 ? " = fastest" : "") << ")";
  if (handshake_) {
    o << "; lossless: " << handshake_->answered() << " samples answered on " << handshake_->topic()
      << ", " << handshake_->unanswered() << " timed out";
    if (const auto last = handshake_->lastEstimate()) {
      o << "; last estimate: " << describeEstimate(*last);
    }
  }
  return o.str();
}

}  // namespace pc_ekf
