// Bags in the layout of docs/method.md §8.2 (rosbag C++ API; ROS-dependent, part of
// pc_ekf_ros, not of the ROS-free pc_ekf_io):
//   road/profile             pc_ekf/RoadProfile       road heights under the tyres
//   suspension/joint_states  sensor_msgs/JointState   the samples (u = position, v = velocity)
//   imu/data                 sensor_msgs/Imu          body IMU (when measurement.channels
//                                                     select IMU channels), aligned to the
//                                                     samples by alignImuRecord (imu_alignment.h)
//   odom                     nav_msgs/Odometry        forward speed twist.twist.linear.x (when
//                                                     measurement.channels select speed),
//                                                     aligned by the same rule
//   ground_truth             pc_ekf/ParameterEstimate true values (synthesize_bag only)
// Topics match on their suffix, so a leading namespace (/car1/road/profile)
// is accepted. Times are header stamps; t = 0 is the stamp of the first
// road/profile message (the vehicle at rest, docs/method.md §8.1).
#pragma once

#include <pc_ekf/ParameterEstimate.h>
#include <ros/time.h>

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "pc_ekf/filter/measurement.h"
#include "pc_ekf/io/estimator_config.h"
#include "pc_ekf/io/measurement_csv.h"
#include "pc_ekf/ros/message_conversion.h"

namespace pc_ekf {

// A bag that cannot be used; the message starts with the file name and
// says what is wrong.
class BagError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

constexpr const char* kRoadTopic = "road/profile";
constexpr const char* kRoadHeightsTopic = "road/heights";
constexpr const char* kJointStatesTopic = "suspension/joint_states";
constexpr const char* kGroundTruthTopic = "ground_truth";
constexpr const char* kImuTopic = "imu/data";
constexpr const char* kOdomTopic = "odom";

// True when `topic` is `suffix`, "/" + suffix, or ends in "/" + suffix.
bool topicMatches(const std::string& topic, const std::string& suffix);

struct BagReadOptions {
  SuspensionJoints joints;
  // The model's contact names: empty = a two-contact road on road_topic
  // (pc_ekf/RoadProfile); else the road is read from road_heights_topic
  // (pc_ekf/RoadHeights) in this order.
  std::vector<std::string> contacts;
  std::string road_topic = kRoadTopic;  // suffixes
  std::string road_heights_topic = kRoadHeightsTopic;
  std::string joint_states_topic = kJointStatesTopic;
  std::string ground_truth_topic = kGroundTruthTopic;
  // IMU channels to read from imu_topic (none: the topic is not read).
  ImuChannels imu;
  std::string imu_topic = kImuTopic;
  double imu_max_gap = 0.1;  // s (node.imu_max_gap; also the odom stream's)
  // The speed channel to read from odom_topic (-1: the topic is not read).
  int odom_speed = -1;
  std::string odom_topic = kOdomTopic;
  // Road-free (road.source none): no road is read, and t = 0 lies one
  // sample interval before the first joint_states stamp, the interval
  // between the first two stamps, as the node's (never the config's
  // sampling:, which describes synthetic drives only).
  bool road_free = false;
};

struct BagRecord {
  ros::Time origin;           // stamp of the first road message (t = 0)
  // The road under every contact (road/profile: left, right), t in s since
  // the origin, strictly increasing.
  ContactSeries road_contacts;
  MeasurementSeries samples;  // t in s since origin, strictly increasing, non-empty
  std::optional<ParameterEstimate> ground_truth;  // the last one, when present
  std::string road_topic, joint_states_topic;     // the topics actually read
  // Elements skipped while converting JointStates (unknown joints, +-Inf,
  // wrong array lengths) and samples with no observed channel, one line each.
  std::vector<std::string> warnings;
  int skipped_elements = 0;
  int empty_samples = 0;
  // IMU (options.imu selected): the topic read ("" = none in the bag), its
  // messages, those that gave no usable channel, and how the samples aligned.
  std::string imu_topic;
  int imu_messages = 0, imu_empty = 0, imu_problems = 0;
  ImuAlignmentCounts imu;
  // Odometry (options.odom_speed >= 0): as the IMU's.
  std::string odom_topic;
  int odom_messages = 0, odom_empty = 0, odom_problems = 0;
  ImuAlignmentCounts odom;
};

// Reads and validates a bag. Throws BagError (naming the file) for a missing,
// unreadable, truncated or corrupt bag; no road/profile or joint_states
// messages; several topics matching one suffix or a matching topic of the
// wrong type; two road messages with the same stamp; samples stamped before
// the first road message; two samples with the same stamp observing the
// same channel (samples with the same stamp and disjoint channels merge).
BagRecord readBag(const std::string& path, const BagReadOptions& options = {});

// How a config's model reads bags: two-contact models the defaults
// (road/profile, left/right joints), others road/heights with the model's
// contacts and node.joints.
BagReadOptions bagReadOptions(const EstimatorConfig& config);

// What writeBag writes: road samples and measurement samples at
// origin + t (header stamp = bag record time), and an optional ground truth.
struct BagContents {
  ros::Time origin;
  // The road under `contacts` (road/heights); with `contacts` empty, two
  // columns (left, right) written as road/profile.
  ContactSeries road_contacts;
  std::vector<std::string> contacts;
  std::string road_heights_topic = kRoadHeightsTopic;
  MeasurementSeries samples;
  std::optional<ParameterEstimate> ground_truth;  // written at its header stamp
  // A truth that changes (synthesize_bag with a truth.schedule): one further
  // ground truth per sample, written at the sample's stamp before the road
  // and samples of later stamps: the last of ground_truth_changes whose
  // `time` is at or before the sample's time (times increasing, the first at
  // or before every sample), with header stamp, sample_index (k + 1) and time
  // the sample's. Held once per change, so a long record costs no memory per
  // sample. Empty: no per-sample ground truth.
  std::vector<ParameterEstimate> ground_truth_changes;
  SuspensionJoints joints;
  std::string road_topic = kRoadTopic;  // full topic names as written
  std::string joint_states_topic = kJointStatesTopic;
  std::string ground_truth_topic = kGroundTruthTopic;
  // Body IMU messages (sensor_msgs/Imu) at the times of imu_samples (their
  // IMU channels; stamps distinct from each other), merged with the rest by
  // stamp. `imu_variances` (one per model channel, may be empty) fill the
  // covariances' diagonals, else they are all zero ("unknown").
  MeasurementSeries imu_samples;
  ImuChannels imu;
  std::vector<double> imu_variances;
  std::string imu_topic = kImuTopic;
  // Odometry messages (nav_msgs/Odometry, twist.twist.linear.x = the
  // channel odom_speed) at the times of odom_samples; the variance from
  // imu_variances[odom_speed] when given, else the covariance all zero.
  MeasurementSeries odom_samples;
  int odom_speed = -1;
  std::string odom_topic = kOdomTopic;
};

// Writes (overwrites) an uncompressed bag. Throws BagError naming the file.
void writeBag(const std::string& path, const BagContents& contents);

}  // namespace pc_ekf
