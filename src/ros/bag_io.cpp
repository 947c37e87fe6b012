#include "pc_ekf/ros/bag_io.h"

#include <ros/message_traits.h>
#include <ros/serialization.h>
#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <rosbag/view.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <iomanip>
#include <optional>
#include <set>
#include <sstream>

#include "pc_ekf/ros/bag_check.h"
#include "pc_ekf/ros/bag_topics.h"

namespace pc_ekf {

namespace {

using namespace bag_topics;

// Road messages as read: stamps and heights only, sorted by stamp once all
// are in.
struct RoadRows {
  std::vector<ros::Time> stamps;
  std::vector<double> heights;  // per message: one per contact
  std::vector<std::pair<std::size_t, std::string>> problems;  // (message, why), message order
  // Message indices by stamp (stable: equal stamps in message order).
  std::vector<std::size_t> byStamp() const {
    std::vector<std::size_t> order(stamps.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(),
                     [this](std::size_t a, std::size_t b) { return stamps[a] < stamps[b]; });
    return order;
  }
};

// Samples with equal stamps observing disjoint channels become one sample.
MeasurementSeries mergeEqualStamps(const std::string& path, std::vector<StampedSample>& raw,
                                   int channels, std::vector<std::int64_t>* stamps) {
  std::stable_sort(raw.begin(), raw.end(),
                   [](const StampedSample& a, const StampedSample& b) { return a.ns < b.ns; });
  MeasurementSeries out;
  out.reserve(raw.size());
  stamps->reserve(raw.size());
  for (std::size_t i = 0; i < raw.size();) {
    std::size_t j = i + 1;
    while (j < raw.size() && raw[j].ns == raw[i].ns) ++j;
    out.push_back(mergeStampGroup(path, raw.data() + i, raw.data() + j, channels));
    stamps->push_back(raw[i].ns);
    i = j;
  }
  return out;
}

// Road: by header stamp; the first stamp is the time origin.
void readTwoContactRoad(const std::string& path, BagRecord& record, const RoadRows& rows) {
  const std::vector<std::size_t> order = rows.byStamp();
  record.origin = rows.stamps[order.front()];
  record.road_contacts.heights.resize(2);
  for (std::size_t i = 0; i < order.size(); ++i) {
    const std::size_t r = order[i];
    const ros::Time& stamp = rows.stamps[r];
    if (i > 0 && stamp == rows.stamps[order[i - 1]]) {
      throw BagError(path + ": two '" + record.road_topic + "' messages stamped " +
                     stampText(stamp));
    }
    const double left = rows.heights[2 * r], right = rows.heights[2 * r + 1];
    if (!std::isfinite(left) || !std::isfinite(right)) {
      throw BagError(path + ": '" + record.road_topic + "' message stamped " + stampText(stamp) +
                     " has a non-finite height");
    }
    const double t = secondsSince(stamp, record.origin);
    record.road_contacts.t.push_back(t);
    record.road_contacts.heights[0].push_back(left);
    record.road_contacts.heights[1].push_back(right);
  }
}

void readContactRoad(const std::string& path, BagRecord& record, const RoadRows& rows,
                     const std::vector<std::string>& contacts) {
  const std::vector<std::size_t> order = rows.byStamp();
  record.origin = rows.stamps[order.front()];
  record.road_contacts.heights.resize(contacts.size());
  for (std::size_t i = 0; i < order.size(); ++i) {
    const std::size_t r = order[i];
    const ros::Time& stamp = rows.stamps[r];
    if (i > 0 && stamp == rows.stamps[order[i - 1]]) {
      throw BagError(path + ": two '" + record.road_topic + "' messages stamped " +
                     stampText(stamp));
    }
    const auto problem = std::lower_bound(
        rows.problems.begin(), rows.problems.end(), r,
        [](const std::pair<std::size_t, std::string>& p, std::size_t m) { return p.first < m; });
    if (problem != rows.problems.end() && problem->first == r) {
      throw BagError(path + ": '" + record.road_topic + "' message stamped " + stampText(stamp) +
                     ": " + problem->second);
    }
    record.road_contacts.t.push_back(secondsSince(stamp, record.origin));
    for (std::size_t c = 0; c < contacts.size(); ++c) {
      record.road_contacts.heights[c].push_back(rows.heights[r * contacts.size() + c]);
    }
  }
}

// The IMU channels (or, for odom, the speed) of every sample by the rule of
// imu_alignment.h (the node's), the stream's messages read one at a time:
// each sample is aligned once a reading at or after its stamp is in (as
// alignImuRecord with every reading, which is what the node does live), and
// readings no later sample needs go.
struct AlignedTopic {
  const char* what;     // "IMU channels" | "the speed"
  const char* message;  // "sensor_msgs/Imu" | "nav_msgs/Odometry"
  const std::string& suffix;
  const std::string& topic;  // "" = none in the bag
  int& messages;
  int& empty;
  int& problems;
  ImuAlignmentCounts& counts;
};

template <class Msg, class Convert>
void alignBagStream(const std::string& path, rosbag::Bag& bag, double max_gap,
                    const std::vector<std::int64_t>& stamps, BagRecord& record,
                    const AlignedTopic& t, Convert convert) {
  if (t.topic.empty()) {
    record.warnings.push_back(std::string("measurement.channels select ") + t.what + " but " +
                              path + " has no " + t.message + " on a topic ending in '" +
                              t.suffix + "': samples without " + t.what);
    return;
  }
  ImuAligner aligner(max_gap);
  ImuAlignmentCounts& n = t.counts;
  std::size_t next = 0;
  const auto alignReady = [&](bool all) {
    for (; next < record.samples.size() && (all || aligner.ready(stamps[next])); ++next) {
      n.count(aligner.align(record.samples[next], stamps[next]));
    }
  };
  try {
    // Bag (record) order: the order a live node receives them in.
    readTopic<Msg>(path, bag, t.topic, [&](const Msg& msg) {
      ++t.messages;
      ImuConversion c = convert(msg);
      t.problems += static_cast<int>(c.problems.size());
      for (const auto& p : c.problems) {
        record.warnings.push_back("'" + t.topic + "' message stamped " +
                                  stampText(msg.header.stamp) + ": " + p);
      }
      if (c.empty()) {
        ++t.empty;
        return;
      }
      if (!aligner.add(std::move(c.reading))) ++n.readings_refused;
      alignReady(false);
    });
  } catch (const BagError&) {
    throw;
  } catch (const std::exception& e) {
    throw BagError(path + ": corrupt or truncated bag: " + e.what());
  }
  alignReady(true);
  if (n.readings_refused > 0) {
    record.warnings.push_back(std::to_string(n.readings_refused) + " '" + t.topic +
                              "' message(s) stamped at or before the previous one: not used");
  }
  const std::string short_name = t.what == std::string("the speed") ? "odom" : "IMU";
  if (n.no_bracket + n.gap > 0) {
    record.warnings.push_back(std::to_string(n.no_bracket) + " sample(s) without " + short_name +
                              " readings on both sides and " + std::to_string(n.gap) +
                              " with " + short_name + " readings more than " +
                              std::to_string(max_gap) +
                              " s apart around them (node.imu_max_gap): no " + t.what + " there");
  }
}

void alignBagImu(const std::string& path, rosbag::Bag& bag, const BagReadOptions& options,
                 const std::vector<std::int64_t>& stamps, BagRecord& record) {
  const AlignedTopic t{"IMU channels",       "sensor_msgs/Imu",   options.imu_topic,
                       record.imu_topic,     record.imu_messages, record.imu_empty,
                       record.imu_problems,  record.imu};
  alignBagStream<sensor_msgs::Imu>(path, bag, options.imu_max_gap, stamps, record, t,
                                   [&](const sensor_msgs::Imu& m) { return readingFromImu(m, options.imu); });
}

void alignBagOdom(const std::string& path, rosbag::Bag& bag, const BagReadOptions& options,
                  const std::vector<std::int64_t>& stamps, BagRecord& record) {
  const AlignedTopic t{"the speed",          "nav_msgs/Odometry",  options.odom_topic,
                       record.odom_topic,    record.odom_messages, record.odom_empty,
                       record.odom_problems, record.odom};
  alignBagStream<nav_msgs::Odometry>(
      path, bag, options.imu_max_gap, stamps, record, t,
      [&](const nav_msgs::Odometry& m) { return readingFromOdometry(m, options.odom_speed); });
}

}  // namespace

bool topicMatches(const std::string& topic, const std::string& suffix) {
  if (suffix.empty()) return false;
  const std::string bare = suffix.front() == '/' ? suffix.substr(1) : suffix;
  if (topic == bare || topic == "/" + bare) return true;
  const std::string tail = "/" + bare;
  return topic.size() > tail.size() &&
         topic.compare(topic.size() - tail.size(), tail.size(), tail) == 0;
}

BagRecord readBag(const std::string& path, const BagReadOptions& options) {
  BagRecord record;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw BagError(path + ": no such bag file");
  }
  // rosbag trusts the lengths and offsets in the file (bag_check.h).
  const std::string problem = bagStructureProblem(path);
  if (!problem.empty()) throw BagError(path + ": corrupt, truncated or unsupported bag: " + problem);
  rosbag::Bag bag;
  try {
    bag.open(path, rosbag::bagmode::Read);
  } catch (const std::exception& e) {
    throw BagError(
        path +
        ": cannot open as a ROS bag (missing, unreadable, truncated or not a bag): " + e.what());
  }

  // Every message is converted as it is read; what is kept is the road's
  // numbers, the samples (bag order, their times set once the origin is
  // known) and the last ground truth.
  const bool road_free = options.road_free;
  RoadRows road;
  std::vector<StampedSample> raw;
  std::vector<std::string> sample_warnings;  // bag order, reported after the road's checks
  std::size_t joint_messages = 0;
  ros::Time first_joint;                    // the earliest joint_states stamp
  std::optional<ros::Time> second_joint;    // the next later one
  std::optional<ros::Time> first_before_road;  // bag order: the first stamped before the road
  std::optional<ParameterEstimate> last_truth;
  std::vector<std::string> topics;
  try {
    if (!road_free) record.road_topic = options.contacts.empty()
                            ? findTopic<RoadProfile>(path, bag, options.road_topic, &topics)
                            : findTopic<RoadHeights>(path, bag, options.road_heights_topic, &topics);
    record.joint_states_topic =
        findTopic<sensor_msgs::JointState>(path, bag, options.joint_states_topic, &topics);
    // Ground truth is optional: one recorded with an older ParameterEstimate
    // (fewer fields) is left out, not fatal.
    std::string older_truth;
    const std::string truth_topic =
        findTopic<ParameterEstimate>(path, bag, options.ground_truth_topic, &topics, &older_truth);
    if (!older_truth.empty()) {
      record.warnings.push_back("topic '" + older_truth + "' has another definition of "
                                "pc_ekf/ParameterEstimate (an older bag): ground truth not read");
    }
    if (record.road_topic.empty() && !road_free) {
      throw BagError(path + ": no " +
                     (options.contacts.empty() ? "pc_ekf/RoadProfile" : "pc_ekf/RoadHeights") +
                     " messages on a topic ending in '" +
                     (options.contacts.empty() ? options.road_topic : options.road_heights_topic) +
                     "' (the road defines t = 0); topics in the bag: " + join(topics));
    }
    if (record.joint_states_topic.empty()) {
      throw BagError(path + ": no sensor_msgs/JointState messages on a topic ending in '" +
                     options.joint_states_topic + "'; topics in the bag: " + join(topics));
    }
    if (road_free) {
      // No road: the samples alone define the record.
    } else if (options.contacts.empty()) {
      readTopic<RoadProfile>(path, bag, record.road_topic, [&](const RoadProfile& r) {
        road.stamps.push_back(r.header.stamp);
        road.heights.push_back(r.left);
        road.heights.push_back(r.right);
      });
    } else {
      std::vector<double> heights;
      readTopic<RoadHeights>(path, bag, record.road_topic, [&](const RoadHeights& r) {
        const std::string problem = roadHeightsInOrder(r, options.contacts, &heights);
        if (!problem.empty()) {
          road.problems.emplace_back(road.stamps.size(), problem);
          heights.assign(options.contacts.size(), 0.0);
        }
        road.stamps.push_back(r.header.stamp);
        road.heights.insert(road.heights.end(), heights.begin(), heights.end());
      });
    }
    // The road's origin is its earliest stamp: a sample stamped before it is
    // refused (the first in bag order named).
    std::optional<ros::Time> road_origin;
    for (const ros::Time& t : road.stamps) {
      road_origin = road_origin ? std::min(*road_origin, t) : t;
    }
    readTopic<sensor_msgs::JointState>(
        path, bag, record.joint_states_topic, [&](const sensor_msgs::JointState& js) {
          const ros::Time& stamp = js.header.stamp;
          if (joint_messages++ == 0 || stamp < first_joint) {
            if (joint_messages > 1) second_joint = first_joint;
            first_joint = stamp;
          } else if (stamp > first_joint && (!second_joint || stamp < *second_joint)) {
            second_joint = stamp;
          }
          if (road_origin && stamp < *road_origin && !first_before_road) first_before_road = stamp;
          JointStateConversion c = measurementFromJointState(js, 0.0, options.joints);
          for (const auto& p : c.problems) {
            sample_warnings.push_back("sample stamped " + stampText(stamp) + ": " + p);
          }
          record.skipped_elements += static_cast<int>(c.problems.size());
          if (c.empty()) {
            ++record.empty_samples;
            return;
          }
          raw.push_back({nanoseconds(stamp), stamp, std::move(c.measurement)});
        });
    readTopic<ParameterEstimate>(path, bag, truth_topic,
                                 [&](const ParameterEstimate& e) { last_truth = e; });
    if (options.imu.any()) {
      record.imu_topic = findTopic<sensor_msgs::Imu>(path, bag, options.imu_topic, &topics);
    }
    if (options.odom_speed >= 0) {
      record.odom_topic = findTopic<nav_msgs::Odometry>(path, bag, options.odom_topic, &topics);
    }
  } catch (const BagError&) {
    throw;
  } catch (const std::exception& e) {
    throw BagError(path + ": corrupt or truncated bag: " + e.what());
  }
  if (road.stamps.empty() && !road_free) {
    throw BagError(path + ": topic '" + record.road_topic + "' has no messages");
  }
  if (joint_messages == 0) {
    throw BagError(path + ": topic '" + record.joint_states_topic +
                   "' has no messages (no samples)");
  }
  if (road_free) {
    if (!second_joint) {
      throw BagError(path + ": road.source none: one '" + record.joint_states_topic +
                     "' stamp only; the interval between the first two sets t = 0");
    }
    try {
      record.origin = stampAt(first_joint, -secondsSince(*second_joint, first_joint));
    } catch (const std::invalid_argument&) {
      record.origin = ros::Time(0, 0);  // stamps near zero (sim time): t = stamp
    }
  } else if (options.contacts.empty()) {
    readTwoContactRoad(path, record, road);
  } else {
    readContactRoad(path, record, road, options.contacts);
  }
  road = RoadRows();

  // Samples: by header stamp, relative to the road's origin.
  if (first_before_road) {
    const ros::Time& stamp = *first_before_road;
    throw BagError(path + ": a '" + record.joint_states_topic + "' message is stamped " +
                   stampText(stamp) + ", " + std::to_string(-secondsSince(stamp, record.origin)) +
                   " s before the first '" + record.road_topic + "' message (" +
                   stampText(record.origin) + ", the time origin t = 0)");
  }
  for (StampedSample& s : raw) s.m.time = secondsSince(s.stamp, record.origin);
  record.warnings.insert(record.warnings.end(), sample_warnings.begin(), sample_warnings.end());
  if (record.empty_samples > 0) {
    record.warnings.push_back(std::to_string(record.empty_samples) +
                              " joint_states message(s) observed no suspension channel; skipped");
  }
  if (raw.empty()) {
    std::string names;
    for (const auto& j : options.joints.resolved()) names += (names.empty() ? "'" : "' or '") + j.name;
    throw BagError(path + ": no '" + record.joint_states_topic + "' message observes " + names +
                   "' (no samples); first problem: " +
                   (record.warnings.empty() ? std::string("none") : record.warnings.front()));
  }
  std::vector<std::int64_t> stamps;
  record.samples = mergeEqualStamps(path, raw, options.joints.channelCount(), &stamps);
  std::vector<StampedSample>().swap(raw);
  if (options.imu.any()) alignBagImu(path, bag, options, stamps, record);
  if (options.odom_speed >= 0) alignBagOdom(path, bag, options, stamps, record);
  record.ground_truth = std::move(last_truth);
  return record;
}

BagReadOptions bagReadOptions(const EstimatorConfig& config) {
  BagReadOptions o;
  o.imu = imuChannels(config.model_type->channelNames(), config.measurement.channels);
  o.imu_max_gap = config.node.imu_max_gap;
  o.odom_speed = odomSpeedChannel(config.model_type->channelNames(), config.measurement.channels);
  o.road_free = config.road.source == RoadSource::kNone;
  if (config.model_type->twoContacts()) return o;
  o.joints = suspensionJoints(*config.model_type, config.node.joint_names);
  o.contacts = config.model_type->contactNames();
  return o;
}

void writeBag(const std::string& path, const BagContents& c) {
  const bool contacts = !c.contacts.empty();
  const std::vector<double>& road_t = c.road_contacts.t;
  // Without contact names the road goes out as pc_ekf/RoadProfile (left, right).
  const std::size_t columns = contacts ? c.contacts.size() : 2;
  // No road at all (a road-free recording): no road messages.
  if (c.road_contacts.heights.size() != columns && !(road_t.empty() && c.road_contacts.heights.empty())) {
    throw BagError(path + ": " + std::to_string(c.road_contacts.heights.size()) +
                   " road columns for " + std::to_string(columns) + " contacts");
  }
  for (const auto& h : c.road_contacts.heights) {
    if (h.size() != road_t.size())
      throw BagError(path + ": road time and height series differ in length");
  }
  try {
    rosbag::Bag bag(path, rosbag::bagmode::Write);
    // Merge road and samples by time (road first at equal times) so the bag
    // plays in stamp order whatever the reader's tie-breaking.
    std::size_t r = 0, s = 0;
    if (c.ground_truth) {
      bag.write(c.ground_truth_topic, c.ground_truth->header.stamp, *c.ground_truth);
    }
    // The per-sample ground truths: sample g's from the change in force (change).
    std::size_t g = 0, change = 0;
    const std::vector<ParameterEstimate>& changes = c.ground_truth_changes;
    ParameterEstimate truth;
    const auto truthsUpTo = [&](const ros::Time& stamp) {
      for (; !changes.empty() && g < c.samples.size(); ++g) {
        const double t = c.samples[g].time;
        const ros::Time at = stampAt(c.origin, t);
        if (at > stamp) break;
        while (change + 1 < changes.size() && changes[change + 1].time <= t) ++change;
        truth = changes[change];
        truth.header.stamp = at;
        truth.sample_index = static_cast<std::uint32_t>(g + 1);
        truth.time = t;
        bag.write(c.ground_truth_topic, at, truth);
      }
    };
    std::vector<double> row(c.contacts.size());
    // IMU messages go in before the road and samples of later stamps.
    std::size_t i = 0;
    // Odometry likewise (after the IMU messages of the same stamp).
    std::size_t o = 0;
    const double odom_variance =
        c.odom_speed >= 0 && static_cast<std::size_t>(c.odom_speed) < c.imu_variances.size()
            ? c.imu_variances[static_cast<std::size_t>(c.odom_speed)]
            : 0.0;
    const auto imuUpTo = [&](const ros::Time& stamp) {
      for (; i < c.imu_samples.size(); ++i) {
        const ros::Time at = stampAt(c.origin, c.imu_samples[i].time);
        if (at > stamp) break;
        bag.write(c.imu_topic, at, imuFromMeasurement(c.imu_samples[i], at, c.imu, c.imu_variances));
      }
      for (; o < c.odom_samples.size(); ++o) {
        const ros::Time at = stampAt(c.origin, c.odom_samples[o].time);
        if (at > stamp) break;
        bag.write(c.odom_topic, at,
                  odometryFromMeasurement(c.odom_samples[o], at, c.odom_speed, odom_variance));
      }
    };
    while (r < road_t.size() || s < c.samples.size()) {
      const bool road_next =
          s >= c.samples.size() || (r < road_t.size() && road_t[r] <= c.samples[s].time);
      truthsUpTo(stampAt(c.origin, road_next ? road_t[r] : c.samples[s].time));
      imuUpTo(stampAt(c.origin, road_next ? road_t[r] : c.samples[s].time));
      if (road_next) {
        const ros::Time stamp = stampAt(c.origin, road_t[r]);
        if (contacts) {
          for (std::size_t k = 0; k < row.size(); ++k) row[k] = c.road_contacts.heights[k][r];
          bag.write(c.road_heights_topic, stamp, roadHeightsMessage(stamp, c.contacts, row));
        } else {
          bag.write(c.road_topic, stamp,
                    roadProfileMessage(stamp, c.road_contacts.heights[0][r],
                                       c.road_contacts.heights[1][r]));
        }
        ++r;
      } else {
        const ros::Time stamp = stampAt(c.origin, c.samples[s].time);
        bag.write(c.joint_states_topic, stamp,
                  jointStateFromMeasurement(c.samples[s], stamp, c.joints));
        ++s;
      }
    }
    imuUpTo(ros::TIME_MAX);
    truthsUpTo(ros::TIME_MAX);
    bag.close();
  } catch (const BagError&) {
    throw;
  } catch (const std::exception& e) {
    throw BagError(path + ": cannot write bag: " + e.what());
  }
}

}  // namespace pc_ekf
