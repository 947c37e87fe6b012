#include "pc_ekf/ros/bag_stream.h"

#include <rosbag/bag.h>

#include <deque>
#include <filesystem>
#include <memory>
#include <optional>
#include <utility>

#include "pc_ekf/filter/imu_alignment.h"
#include "pc_ekf/ros/bag_topics.h"
#include "pc_ekf/ros/message_conversion.h"

namespace pc_ekf {
namespace {

using namespace bag_topics;

// The first few of a kind of warning, and how many.
struct Kept {
  std::vector<std::string> first;
  std::size_t count = 0;
  void add(std::string w) {
    if (first.size() < RecordStream::kKeptWarnings) first.push_back(std::move(w));
    ++count;
  }
};

// One aligned topic (IMU or odometry) as alignBagStream reads it. A sample
// is aligned once a reading at or after its stamp is in (or none is left);
// readings that come in after that one change nothing a sample's alignment
// reads, so the samples may wait for the slower of the two topics.
template <class Msg>
struct AlignedReader {
  const char* what;  // "IMU channels" | "the speed"
  const char* short_name;
  std::string topic;
  ImuAligner aligner;
  std::function<ImuConversion(const Msg&)> convert;
  ImuAlignmentCounts counts;
  Kept warnings;
  std::size_t read = 0;
  bool done = false;  // every message read
  Msg msg;

  AlignedReader(const char* w, const char* s, const std::string& t, double max_gap,
                std::function<ImuConversion(const Msg&)> c)
      : what(w), short_name(s), topic(t), aligner(max_gap), convert(std::move(c)) {}

  void take(const std::string& path, const rosbag::MessageInstance& m, std::vector<std::uint8_t>& bytes) {
    decodeMessage(path, m, read++, bytes, &msg);
    ImuConversion c = convert(msg);
    for (const auto& p : c.problems) {
      warnings.add("'" + topic + "' message stamped " + stampText(msg.header.stamp) + ": " + p);
    }
    if (c.empty()) return;
    if (!aligner.add(std::move(c.reading))) ++counts.readings_refused;
  }
  bool ready(std::int64_t ns) const { return done || aligner.ready(ns); }
  void align(Measurement& m, std::int64_t ns) { counts.count(aligner.align(m, ns)); }
  // readBag's lines after the messages' own.
  void summary(double max_gap) {
    if (counts.readings_refused > 0) {
      warnings.add(std::to_string(counts.readings_refused) + " '" + topic +
                   "' message(s) stamped at or before the previous one: not used");
    }
    if (counts.no_bracket + counts.gap > 0) {
      warnings.add(std::to_string(counts.no_bracket) + " sample(s) without " + short_name +
                   " readings on both sides and " + std::to_string(counts.gap) + " with " +
                   short_name + " readings more than " + std::to_string(max_gap) +
                   " s apart around them (node.imu_max_gap): no " + what + " there");
    }
  }
};

class BagRecordStream : public RecordStream {
 public:
  BagRecordStream(std::string path, BagReadOptions options)
      : path_(std::move(path)), options_(std::move(options)) {}

  bool read(const std::function<void(Measurement&)>& take) override {
    if (!options_.road_free) return false;
    if (passes_++ > 0) return readOnce(take, false);
    // The first pass finds whatever readBag would refuse; readBag then says it.
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path_, ec) || !bagStructureProblem(path_).empty()) {
      return false;
    }
    try {
      return readOnce(take, true);
    } catch (const std::exception&) {
      return false;
    }
  }

 private:
  // `first`: also what readBag reads but the samples do not need.
  bool readOnce(const std::function<void(Measurement&)>& take, bool first);

  std::string path_;
  BagReadOptions options_;
  int passes_ = 0;
  // Opened once: rosbag loads every message's index entry on opening.
  std::unique_ptr<rosbag::Bag> bag_;
};

bool BagRecordStream::readOnce(const std::function<void(Measurement&)>& take, bool first) {
  const std::string& path = path_;
  if (!bag_) {
    bag_ = std::make_unique<rosbag::Bag>();
    bag_->open(path, rosbag::bagmode::Read);
  }
  rosbag::Bag& bag = *bag_;
  std::vector<std::string> topics;
  const std::string joint_topic =
      findTopic<sensor_msgs::JointState>(path, bag, options_.joint_states_topic, &topics);
  std::string older_truth;
  const std::string truth_topic =
      findTopic<ParameterEstimate>(path, bag, options_.ground_truth_topic, &topics, &older_truth);
  if (joint_topic.empty()) throw BagError(path + ": no joint_states topic");
  // Read as readBag reads them (a message that cannot be decoded is refused).
  if (first) readTopic<ParameterEstimate>(path, bag, truth_topic, [](const ParameterEstimate&) {});
  const std::string imu_topic =
      options_.imu.any() ? findTopic<sensor_msgs::Imu>(path, bag, options_.imu_topic, &topics) : "";
  const std::string odom_topic =
      options_.odom_speed >= 0
          ? findTopic<nav_msgs::Odometry>(path, bag, options_.odom_topic, &topics)
          : "";
  const double gap = options_.imu_max_gap;
  std::optional<AlignedReader<sensor_msgs::Imu>> imu;
  std::optional<AlignedReader<nav_msgs::Odometry>> odom;
  std::vector<std::string> topics_read{joint_topic};
  if (!imu_topic.empty()) {
    imu.emplace("IMU channels", "IMU", imu_topic, gap,
                [this](const sensor_msgs::Imu& m) { return readingFromImu(m, options_.imu); });
    topics_read.push_back(imu_topic);
  }
  if (!odom_topic.empty()) {
    odom.emplace("the speed", "odom", odom_topic, gap, [this](const nav_msgs::Odometry& m) {
      return readingFromOdometry(m, options_.odom_speed);
    });
    topics_read.push_back(odom_topic);
  }

  // Samples of one stamp are merged (readBag's stable sort keeps bag order
  // within a stamp); t = 0 needs the second distinct stamp, so the first
  // stamp's samples are merged only once a later stamp has come (and set it).
  Kept sample_warnings;
  std::size_t joint_messages = 0, samples = 0;
  int empty_samples = 0;
  ros::Time first_joint, last_stamp;
  std::optional<ros::Time> origin;
  std::vector<StampedSample> group;
  std::deque<StampedSample> pending;  // merged, waiting for their IMU or odometry
  const int channels = options_.joints.channelCount();
  const auto emitReady = [&] {
    while (!pending.empty() && (!imu || imu->ready(pending.front().ns)) &&
           (!odom || odom->ready(pending.front().ns))) {
      StampedSample& s = pending.front();
      if (imu) imu->align(s.m, s.ns);
      if (odom) odom->align(s.m, s.ns);
      ++samples;
      take(s.m);
      pending.pop_front();
    }
  };
  const auto flush = [&] {
    if (group.empty()) return;
    if (!origin) throw BagError(path + ": one joint_states stamp only");
    pending.push_back({group.front().ns, group.front().stamp,
                       mergeStampGroup(path, group.data(), group.data() + group.size(), channels)});
    pending.back().m.time = secondsSince(pending.back().stamp, *origin);
    group.clear();
    emitReady();
  };
  // One view over the topics: each chunk of the bag is read once.
  rosbag::View view(bag, rosbag::TopicQuery(topics_read));
  std::vector<std::uint8_t> bytes;
  sensor_msgs::JointState js;
  for (const rosbag::MessageInstance& message : view) {
    const std::string& topic = message.getTopic();
    if (imu && topic == imu->topic) {
      imu->take(path, message, bytes);
      emitReady();
      continue;
    }
    if (odom && topic == odom->topic) {
      odom->take(path, message, bytes);
      emitReady();
      continue;
    }
    decodeMessage(path, message, joint_messages, bytes, &js);
    const ros::Time stamp = js.header.stamp;
    if (joint_messages++ == 0) {
      first_joint = stamp;
    } else if (stamp < last_stamp) {
      return false;  // readBag sorts them: read whole
    } else if (!origin && stamp > first_joint) {
      try {
        origin = stampAt(first_joint, -secondsSince(stamp, first_joint));
      } catch (const std::invalid_argument&) {
        origin = ros::Time(0, 0);  // stamps near zero (sim time): t = stamp
      }
    }
    last_stamp = stamp;
    JointStateConversion c = measurementFromJointState(js, 0.0, options_.joints);
    for (const auto& p : c.problems) sample_warnings.add("sample stamped " + stampText(stamp) + ": " + p);
    if (c.empty()) {
      ++empty_samples;
      continue;
    }
    if (!group.empty() && group.front().ns != nanoseconds(stamp)) flush();
    group.push_back({nanoseconds(stamp), stamp, std::move(c.measurement)});
  }
  if (!origin) throw BagError(path + ": one joint_states stamp only");
  flush();
  if (imu) imu->done = true;
  if (odom) odom->done = true;
  emitReady();
  if (samples == 0) throw BagError(path + ": no samples");

  // readBag's warnings, in its order.
  std::vector<Kept> kinds(1);
  if (!older_truth.empty()) {
    kinds[0].add("topic '" + older_truth + "' has another definition of "
                 "pc_ekf/ParameterEstimate (an older bag): ground truth not read");
  }
  kinds.push_back(std::move(sample_warnings));
  if (empty_samples > 0) {
    kinds.emplace_back().add(std::to_string(empty_samples) +
                             " joint_states message(s) observed no suspension channel; skipped");
  }
  const auto aligned = [&](auto& reader, bool selected, const char* what, const char* message,
                           const std::string& suffix) {
    if (!selected) return;
    if (!reader) {
      kinds.emplace_back().add(std::string("measurement.channels select ") + what + " but " +
                               path + " has no " + message + " on a topic ending in '" + suffix +
                               "': samples without " + what);
      return;
    }
    reader->summary(gap);
    kinds.push_back(std::move(reader->warnings));
  };
  aligned(imu, options_.imu.any(), "IMU channels", "sensor_msgs/Imu", options_.imu_topic);
  aligned(odom, options_.odom_speed >= 0, "the speed", "nav_msgs/Odometry", options_.odom_topic);
  warnings_.clear();
  warning_count_ = 0;
  for (const Kept& k : kinds) {
    for (const std::string& w : k.first) {
      if (warnings_.size() < kKeptWarnings) warnings_.push_back(w);
    }
    warning_count_ += k.count;
  }
  return true;
}

}  // namespace

std::unique_ptr<RecordStream> bagRecordStream(const std::string& path,
                                              const BagReadOptions& options) {
  return std::make_unique<BagRecordStream>(path, options);
}

}  // namespace pc_ekf
