// Conversion between ROS messages and the ROS-free core types: time stamps,
// suspension JointState -> Measurement, road samples, and the core's
// estimates -> pc_ekf/ParameterEstimate and pc_ekf/ParameterPdf.
// No node logic here: the node and the bag tools share these functions.
#pragma once

#include <pc_ekf/ParameterEstimate.h>
#include <pc_ekf/ParameterPdf.h>
#include <pc_ekf/RoadHeights.h>
#include <pc_ekf/RoadProfile.h>
#include <nav_msgs/Odometry.h>
#include <ros/time.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/JointState.h>

#include <Eigen/Dense>
#include <string>
#include <vector>

#include "pc_ekf/filter/health.h"
#include "pc_ekf/filter/imu_alignment.h"
#include "pc_ekf/filter/measurement.h"
#include "pc_ekf/filter/one_step_filter.h"
#include "pc_ekf/health/predictive_check.h"
#include "pc_ekf/filter/rollover_quantities.h"
#include "pc_ekf/filter/uncertain_parameters.h"
#include "pc_ekf/model/model_type.h"
#include "pc_ekf/pc/pc_statistics.h"
#include "pc_ekf/pc/polynomial_basis.h"

namespace pc_ekf {

// ---- time: seconds since the time origin (docs/method.md §8.1) ----

// (stamp - origin) in seconds, from the exact nanosecond difference, so
// stamps written by stampAt() give back the same double for times that are
// whole nanoseconds (k * 0.03 s and the like).
double secondsSince(const ros::Time& stamp, const ros::Time& origin);
// origin + t, rounded to the nearest nanosecond. Throws std::invalid_argument
// when t is not finite or the result is outside ros::Time's range.
ros::Time stampAt(const ros::Time& origin, double t);
// Seconds (e.g. a command-line --start-time) to a ros::Time, nanosecond
// rounding; throws std::invalid_argument when not finite or not in [0, 2^32).
ros::Time timeFromSeconds(double seconds);

// ---- suspension measurements (sensor_msgs/JointState) ----

// Joint names of the suspensions and the channels each carries (from the
// model's description, names configurable). Default: the default model
// type's joints with their default names (the roll plane's left and right).
struct SuspensionJoints {
  struct Joint {
    std::string name;
    int position = -1, velocity = -1;  // channel indices (-1: the field is not measured)
  };
  SuspensionJoints();
  SuspensionJoints(std::vector<Joint> joints, int channels)
      : joints(std::move(joints)), channels(channels) {}
  std::vector<Joint> joints;
  int channels = 0;  // the model's channel count
  const std::vector<Joint>& resolved() const { return joints; }
  int channelCount() const { return channels; }
};

// The joints of a model type with the configured names (node.joint_names).
SuspensionJoints suspensionJoints(const ModelType& type, const std::vector<std::string>& names);

// Why an element or array of a JointState was not used (node counters).
enum class JointStateProblem { kArrayLength, kUnknownJoint, kDuplicateJoint, kNonFinite };

struct JointStateConversion {
  // Channels with a finite value, ascending; `time` is the caller's t.
  // NaN (and absent arrays or joints) mean "not observed" and are not problems.
  Measurement measurement;
  // One line per rejected element or array: unknown joint name, duplicate
  // joint, position/velocity array length different from name's, +-Inf.
  // The rest of the message is still converted.
  std::vector<std::string> problems;
  std::vector<JointStateProblem> problem_kinds;  // parallel to `problems`
  int nan_elements = 0;  // NaN values of the named joints (not observed)
  bool empty() const { return measurement.channels.empty(); }
};

// Converts one JointState taken at `time` (s since the origin):
// position = u (m), velocity = v (m/s) of the named joints; effort ignored.
JointStateConversion measurementFromJointState(const sensor_msgs::JointState& msg, double time,
                                               const SuspensionJoints& joints = {});

// The inverse, for writing bags: names {left, right}, position [u1, u2],
// velocity [v1, v2], NaN where a channel is not observed. Throws
// std::invalid_argument for a channel index outside 0..3 or a size mismatch.
sensor_msgs::JointState jointStateFromMeasurement(const Measurement& m, const ros::Time& stamp,
                                                  const SuspensionJoints& joints = {});

// ---- body IMU (sensor_msgs/Imu on imu/data, REP 145 raw) ----

// The model channels an Imu message fills: linear_acceleration.y, .z ->
// accel_y, accel_z; angular_velocity.x, .y, .z -> gyro_x, gyro_y, gyro_z
// (gyro_z: the yaw rate, REP 103; -1: not selected or not a channel of the
// model; accel_x from .x where a model has it).
struct ImuChannels {
  int accel_x = -1, accel_y = -1, accel_z = -1, gyro_x = -1, gyro_y = -1, gyro_z = -1;
  bool any() const {
    return accel_x >= 0 || accel_y >= 0 || accel_z >= 0 || gyro_x >= 0 || gyro_y >= 0 ||
           gyro_z >= 0;
  }
  bool has(int channel) const {
    return channel >= 0 && (channel == accel_x || channel == accel_y || channel == accel_z ||
                            channel == gyro_x || channel == gyro_y || channel == gyro_z);
  }
};
// The IMU channels of `channel_names` (the model's) that `selected`
// (measurement.channels) selects.
ImuChannels imuChannels(const std::vector<std::string>& channel_names,
                        const std::vector<std::string>& selected);

enum class ImuProblem {
  kNonFinite,         // a used value NaN/Inf: that channel not observed
  kNoData,            // covariance element 0 = -1: that field's channels not observed
  kBadCovariance,     // a used diagonal entry NaN/Inf/negative: config noise used
};
const char* toString(ImuProblem p);

struct ImuConversion {
  ImuReading reading;  // stamp_ns = header stamp in ns
  // Per field (linear_acceleration, angular_velocity): its covariance was all
  // zero ("unknown"): the config's noise used.
  int unknown_covariances = 0;
  std::vector<std::string> problems;  // one line each
  std::vector<ImuProblem> problem_kinds;
  bool empty() const { return reading.channels.empty(); }
};

// Converts one Imu message. Covariances: the diagonal entry of each used
// axis is the reading's variance; an all-zero matrix ("unknown") or a zero
// entry gives NaN (the config's noise); element 0 = -1 ("no data") leaves
// that field's channels out. Orientation is not used.
ImuConversion readingFromImu(const sensor_msgs::Imu& msg, const ImuChannels& channels);

// The inverse, for writing bags: the IMU channels of `m` at `stamp`;
// unobserved fields NaN with covariance element 0 = -1; `variances` (one per
// model channel, may be empty) fill the diagonal entries, else all zero.
sensor_msgs::Imu imuFromMeasurement(const Measurement& m, const ros::Time& stamp,
                                    const ImuChannels& channels,
                                    const std::vector<double>& variances = {});

// ---- odometry (nav_msgs/Odometry on odom): the forward speed ----

// The model channel `speed` when `selected` (measurement.channels) selects
// it and the model has it, else -1.
int odomSpeedChannel(const std::vector<std::string>& channel_names,
                     const std::vector<std::string>& selected);

// Converts one Odometry message: twist.twist.linear.x -> the speed channel;
// its variance twist.covariance[0] (all zero: "unknown", NaN: the config's
// noise; a negative or non-finite entry: counted, the config's noise; -1:
// no data, the channel not observed). Problems as readingFromImu's.
ImuConversion readingFromOdometry(const nav_msgs::Odometry& msg, int speed_channel);

// The inverse, for writing bags: the speed channel of `m` at `stamp` (NaN
// when `m` does not observe it); `variance` > 0 fills twist.covariance[0],
// else the covariance is all zero ("unknown").
nav_msgs::Odometry odometryFromMeasurement(const Measurement& m, const ros::Time& stamp,
                                           int speed_channel, double variance = 0.0);

// ---- road ----
RoadProfile roadProfileMessage(const ros::Time& stamp, double left, double right);
RoadHeights roadHeightsMessage(const ros::Time& stamp, const std::vector<std::string>& contacts,
                               const std::vector<double>& heights);
// The heights in the order of `contacts` (the model's); "" or why the message
// does not give each of them exactly once with a finite height.
std::string roadHeightsInOrder(const RoadHeights& msg, const std::vector<std::string>& contacts,
                               std::vector<double>* heights);

// ---- estimates (pc_ekf/ParameterEstimate) ----

// What the core structs do not know: stamp, frame and provenance.
struct EstimateContext {
  ros::Time stamp;       // stamp of the answered sample
  std::string frame_id;  // usually empty
  std::string method = "one_step";
  std::string update_rule;  // "paper" | "square_root" | ""
  // The derived quantities to publish, projected at sample `derived_index`
  // (the node's cadence, node.derived_every); null: projected from this result.
  const DerivedExpansions* derived = nullptr;
  int derived_index = 0;
};

// Batch results: the posterior-predictive check; outside -> not healthy, `warning` added.
void setPredictiveCheck(ParameterEstimate& msg, const PredictiveCheck& p,
                        const std::string& warning);

// The building blocks (the node's batch/EnKF results use them directly):
// names, mean, stddev and their germ coordinates through `mapping`.
void setParameters(ParameterEstimate& msg, const ParameterMapping& mapping,
                   const Eigen::VectorXd& mean, const Eigen::VectorXd& stddev);
// Basis description: germ family/shapes, total degree, multi-indices (row-major).
void setBasis(ParameterEstimate& msg, const PolynomialBasis& basis);
// coefficients (parameters x S) row-major plus term_count; an empty matrix
// clears them.
void setCoefficients(ParameterEstimate& msg, const Eigen::MatrixXd& coefficients);
// Derived quantities (derived_* fields; filter/rollover_quantities.h): names,
// means, stds and row-major coefficients; an empty `d` clears them.
void setDerived(ParameterEstimate& msg, const DerivedExpansions& d);
// The rollover outputs of `coefficients` (parameters x S) when the vehicle
// has heights (none otherwise), derived_sample_index the message's
// sample_index (set it first).
void setRolloverOutputs(ParameterEstimate& msg, const ParameterMapping& mapping,
                        const PolynomialBasis& basis, const Eigen::MatrixXd& coefficients);
// The safeguards' rates (docs/method.md §5.9; empty arrays when not available).
void setRates(ParameterEstimate& msg, const SafeguardRates& rates, double window);
// Health fields of docs/method.md §5 (also sets `healthy` and `warnings`, keeping a
// coherence flag already set).
void setHealth(ParameterEstimate& msg, const HealthStatus& health, int nis_channels,
               const HealthSettings& settings);
// Multi-rate coherence (docs/method.md §5.2): flagged when any disagreement exceeds
// `threshold`; a flag makes the estimate unhealthy and adds a warning.
void setCoherence(ParameterEstimate& msg, const Eigen::VectorXd& disagreement, int decimation,
                  double threshold);

// One processed sample of OneStepFilter: everything above but coherence.
ParameterEstimate estimateMessage(const StepResult& result, const PcPropagator& propagator,
                                  const HealthSettings& health_settings,
                                  const EstimateContext& context);
// The same from the pieces (basis and mapping without a propagator).
ParameterEstimate estimateMessage(const StepResult& result, const PolynomialBasis& basis,
                                  const ParameterMapping& mapping,
                                  const HealthSettings& health_settings,
                                  const EstimateContext& context);

// Ground truth: method "truth", mean = the true values of the mapped
// parameters at germ point `xi_truth`, stddev 0, xi_mean = xi_truth,
// xi_stddev 0, and, with a basis, the constant expansion [value, 0, ..., 0];
// healthy, sample_index 0.
ParameterEstimate groundTruthMessage(const ParameterMapping& mapping,
                                     const Eigen::VectorXd& xi_truth, const PolynomialBasis* basis,
                                     const ros::Time& stamp);

// ---- densities (pc_ekf/ParameterPdf) ----
// `mass_outside` may be empty (zeros) or one per histogram. Throws
// std::invalid_argument when the sizes disagree.
ParameterPdf pdfMessage(const std::vector<std::string>& names,
                        const std::vector<Histogram>& histograms,
                        const std::vector<double>& mass_outside, int sample_index,
                        const ros::Time& stamp);

// ---- reading back (tests, tools) ----
// Coefficients (names.size() x term_count) of a message; throws
// std::invalid_argument when the array has the wrong size.
Eigen::MatrixXd coefficientsOf(const ParameterEstimate& msg);
// The same for derived_coefficients (derived_names.size() x term_count).
Eigen::MatrixXd derivedCoefficientsOf(const ParameterEstimate& msg);

}  // namespace pc_ekf
