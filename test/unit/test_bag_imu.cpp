// Issue 29, the ROS edge: the IMU alignment rule (filter/imu_alignment.h),
// sensor_msgs/Imu conversion (covariances, NaN, -1 "no data"), per-sample
// variances in the noise model, the node's IMU input (ros/imu_input.h: bad
// input counted, nothing else lost) and bags with imu/data.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include "pc_ekf/filter/imu_alignment.h"
#include "pc_ekf/filter/measurement.h"
#include "pc_ekf/io/estimator_config.h"
#include "pc_ekf/ros/bag_io.h"
#include "pc_ekf/ros/imu_input.h"
#include "pc_ekf/ros/message_conversion.h"

namespace pc_ekf {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

ImuReading reading(std::int64_t ns, std::vector<int> channels, std::vector<double> values,
                   std::vector<double> variances = {}) {
  ImuReading r;
  r.stamp_ns = ns;
  r.channels = std::move(channels);
  r.values = Eigen::Map<Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size()));
  if (!variances.empty()) {
    r.variances =
        Eigen::Map<Eigen::VectorXd>(variances.data(), static_cast<Eigen::Index>(variances.size()));
  } else {
    r.variances = Eigen::VectorXd::Constant(r.values.size(), kNaN);
  }
  return r;
}

Measurement suspension(double u1, double u2) {
  Measurement m;
  m.channels = {0, 1};
  m.values = Eigen::Vector2d(u1, u2);
  return m;
}

TEST(ImuAlignment, InterpolatesLinearlyAtTheSampleStampAndMergesChannelsAscending) {
  const ImuReading a = reading(1000, {4, 5, 6}, {1.0, 2.0, 3.0}, {0.01, kNaN, 0.03});
  const ImuReading b = reading(5000, {4, 5, 6}, {3.0, 6.0, 11.0}, {0.05, 0.02, 0.07});
  Measurement m = suspension(0.1, 0.2);
  ASSERT_EQ(addImuChannels(m, 2000, a, b, 10000), ImuAlignment::kAligned);  // w = 1/4
  ASSERT_EQ(m.channels, (std::vector<int>{0, 1, 4, 5, 6}));
  EXPECT_DOUBLE_EQ(m.values[0], 0.1);
  EXPECT_DOUBLE_EQ(m.values[2], 1.5);
  EXPECT_DOUBLE_EQ(m.values[3], 3.0);
  EXPECT_DOUBLE_EQ(m.values[4], 5.0);
  ASSERT_EQ(m.variances.size(), 5);
  EXPECT_TRUE(std::isnan(m.variances[0]));  // suspension: the config's noise
  EXPECT_DOUBLE_EQ(m.variances[2], 0.75 * 0.01 + 0.25 * 0.05);
  EXPECT_TRUE(std::isnan(m.variances[3]));  // one side unknown: the config's noise
  EXPECT_DOUBLE_EQ(m.variances[4], 0.75 * 0.03 + 0.25 * 0.07);
}

TEST(ImuAlignment, AReadingAtTheStampIsTakenAsItIsAndAChannelMissingOnOneSideIsLeftOut) {
  const ImuReading a = reading(1000, {4, 6}, {1.0, 3.0});
  const ImuReading b = reading(3000, {4, 5, 6}, {3.0, 7.0, 5.0});
  Measurement at_b = suspension(0, 0);
  ASSERT_EQ(addImuChannels(at_b, 3000, a, b, 10000), ImuAlignment::kAligned);
  EXPECT_EQ(at_b.channels, (std::vector<int>{0, 1, 4, 5, 6}));
  EXPECT_EQ(at_b.values[3], 7.0);
  EXPECT_EQ(at_b.variances.size(), 0);  // no message variance anywhere: none kept
  Measurement between = suspension(0, 0);
  ASSERT_EQ(addImuChannels(between, 2000, a, b, 10000), ImuAlignment::kAligned);
  EXPECT_EQ(between.channels, (std::vector<int>{0, 1, 4, 6}));
  EXPECT_DOUBLE_EQ(between.values[2], 2.0);
  EXPECT_DOUBLE_EQ(between.values[3], 4.0);
}

TEST(ImuAlignment, ReadingsFurtherApartThanMaxGapAreNotInterpolated) {
  const ImuReading a = reading(0, {4}, {1.0});
  const ImuReading b = reading(200000000, {4}, {2.0});  // 0.2 s
  Measurement m = suspension(0, 0);
  EXPECT_EQ(addImuChannels(m, 100000000, a, b, 100000000), ImuAlignment::kGap);
  EXPECT_EQ(m.channels, (std::vector<int>{0, 1}));
  EXPECT_THROW(addImuChannels(m, 300000000, a, b, 1000000000), std::invalid_argument);
}

TEST(ImuAlignment, StreamingAndWholeRecordGiveTheSameSamplesAndRefuseOutOfOrderReadings) {
  std::vector<ImuReading> imu = {reading(2, {4}, {0.0}), reading(7, {4}, {5.0}),
                                 reading(5, {4}, {100.0}),  // out of order: refused
                                 reading(7, {4}, {100.0}),  // duplicate: refused
                                 reading(12, {4}, {10.0})};
  MeasurementSeries samples = {suspension(1, 1), suspension(2, 2), suspension(3, 3),
                               suspension(4, 4), suspension(5, 5)};
  const std::vector<std::int64_t> stamps = {0, 5, 10, 12, 15};
  ImuAlignmentCounts n;
  const MeasurementSeries out = alignImuRecord(samples, stamps, imu, 1.0, &n);
  EXPECT_EQ(n.readings_refused, 2);
  EXPECT_EQ(n.aligned, 3);     // 5, 10, 12
  EXPECT_EQ(n.no_bracket, 2);  // 0 (before the first), 15 (after the last)
  ASSERT_EQ(out[1].channels.size(), 3u);
  EXPECT_DOUBLE_EQ(out[1].values[2], 3.0);  // 0 + (5 - 2) / 5 * 5
  EXPECT_DOUBLE_EQ(out[2].values[2], 8.0);
  EXPECT_DOUBLE_EQ(out[3].values[2], 10.0);
  EXPECT_EQ(out[0].channels.size(), 2u);
  EXPECT_EQ(out[4].channels.size(), 2u);

  ImuAligner streaming(1.0);
  EXPECT_TRUE(streaming.add(imu[0]));
  EXPECT_TRUE(streaming.add(imu[1]));
  EXPECT_FALSE(streaming.add(imu[2]));
  EXPECT_FALSE(streaming.add(imu[3]));
  Measurement s1 = samples[1];
  ASSERT_TRUE(streaming.ready(5));
  EXPECT_EQ(streaming.align(s1, 5), ImuAlignment::kAligned);
  EXPECT_EQ(s1.values, out[1].values);
  EXPECT_FALSE(streaming.ready(10));  // waits for a reading at or after 10
}

TEST(NoiseModelVariances, AMessageVarianceReplacesTheSensorStdAndNaNKeepsIt) {
  NoiseModel noise;
  noise.rule = NoiseRule::kSensor;
  noise.r_relative = 0.0;
  noise.channel_std = Eigen::VectorXd::Constant(7, 0.1);
  noise.channel_relative = Eigen::VectorXd::Zero(7);
  noise.channel_relative[0] = 0.5;
  Measurement m;
  m.channels = {0, 4, 5};
  m.values = Eigen::Vector3d(2.0, 9.81, 0.1);
  const Eigen::VectorXd without = noise.variances(m);
  EXPECT_DOUBLE_EQ(without[0], 0.01 + 1.0);
  EXPECT_DOUBLE_EQ(without[1], 0.01);
  m.variances = Eigen::Vector3d(0.25, 4e-4, kNaN);
  const Eigen::VectorXd with = noise.variances(m);
  EXPECT_DOUBLE_EQ(with[0], 0.25 + 1.0);  // the relative part stays
  EXPECT_DOUBLE_EQ(with[1], 4e-4);
  EXPECT_DOUBLE_EQ(with[2], 0.01);
  m.variances = Eigen::Vector2d(1, 1);
  EXPECT_THROW(noise.variances(m), std::invalid_argument);
  // onlyChannels keeps the variances with their values.
  m.variances = Eigen::Vector3d(0.25, 4e-4, kNaN);
  const MeasurementSeries kept = onlyChannels(MeasurementSeries{m}, {4, 5});
  ASSERT_EQ(kept[0].variances.size(), 2);
  EXPECT_DOUBLE_EQ(kept[0].variances[0], 4e-4);
}

// Roll plane channels: u1 u2 v1 v2 accel_y accel_z gyro_x = 0..6.
ImuChannels rollPlaneImu() {
  return imuChannels(rollPlaneType()->channelNames(),
                     {"u1", "u2", "v1", "v2", "accel_y", "accel_z", "gyro_x"});
}

sensor_msgs::Imu imuMessage(double ay, double az, double gx) {
  sensor_msgs::Imu msg;
  msg.header.stamp = ros::Time(10, 500);
  msg.linear_acceleration.x = 0.3;
  msg.linear_acceleration.y = ay;
  msg.linear_acceleration.z = az;
  msg.angular_velocity.x = gx;
  return msg;
}

TEST(ImuConversion, ChannelsCovariancesAndBadInput) {
  const ImuChannels ch = rollPlaneImu();
  ASSERT_EQ(ch.accel_y, 4);
  ASSERT_EQ(ch.gyro_x, 6);
  EXPECT_EQ(ch.gyro_y, -1);  // the roll plane has none
  EXPECT_FALSE(imuChannels(rollPlaneType()->channelNames(), {"u1", "u2"}).any());

  // Given covariances: the diagonal entries of the used axes.
  sensor_msgs::Imu msg = imuMessage(0.1, 9.8, 0.02);
  msg.linear_acceleration_covariance[4] = 1e-3;
  msg.linear_acceleration_covariance[8] = 2e-3;
  msg.angular_velocity_covariance[0] = 4e-6;
  ImuConversion c = readingFromImu(msg, ch);
  EXPECT_EQ(c.reading.stamp_ns, 10000000500LL);
  ASSERT_EQ(c.reading.channels, (std::vector<int>{4, 5, 6}));
  EXPECT_EQ(c.reading.values[1], 9.8);
  EXPECT_EQ(c.reading.variances[0], 1e-3);
  EXPECT_EQ(c.reading.variances[2], 4e-6);
  EXPECT_TRUE(c.problems.empty());

  // All zero: "unknown" -> NaN (sensor_std).
  c = readingFromImu(imuMessage(0.1, 9.8, 0.02), ch);
  EXPECT_EQ(c.unknown_covariances, 2);
  EXPECT_TRUE(std::isnan(c.reading.variances[0]) && std::isnan(c.reading.variances[2]));

  // -1: no data for that field; the other field is still used.
  msg = imuMessage(0.1, 9.8, 0.02);
  msg.angular_velocity_covariance[0] = -1.0;
  c = readingFromImu(msg, ch);
  EXPECT_EQ(c.reading.channels, (std::vector<int>{4, 5}));
  ASSERT_EQ(c.problem_kinds, (std::vector<ImuProblem>{ImuProblem::kNoData}));
  EXPECT_NE(c.problems[0].find("angular_velocity_covariance[0] = -1"), std::string::npos);

  // NaN and Inf values: those channels not observed, named.
  c = readingFromImu(imuMessage(kNaN, std::numeric_limits<double>::infinity(), 0.02), ch);
  EXPECT_EQ(c.reading.channels, (std::vector<int>{6}));
  EXPECT_EQ(c.problem_kinds.size(), 2u);
  EXPECT_NE(c.problems[0].find("linear_acceleration.y"), std::string::npos);

  // A negative diagonal entry that is not the -1 flag: config noise, named.
  msg = imuMessage(0.1, 9.8, 0.02);
  msg.linear_acceleration_covariance[4] = -0.5;
  msg.linear_acceleration_covariance[8] = 1e-3;
  c = readingFromImu(msg, ch);
  ASSERT_EQ(c.problem_kinds, (std::vector<ImuProblem>{ImuProblem::kBadCovariance}));
  EXPECT_TRUE(std::isnan(c.reading.variances[0]));
  EXPECT_EQ(c.reading.variances[1], 1e-3);

  // Round trip of the writer.
  Measurement m;
  m.channels = {0, 4, 5, 6};
  m.values = Eigen::Vector4d(0.01, 0.2, 9.7, -0.1);
  const sensor_msgs::Imu written = imuFromMeasurement(m, ros::Time(3, 0), ch, {});
  c = readingFromImu(written, ch);
  EXPECT_EQ(c.reading.channels, (std::vector<int>{4, 5, 6}));
  EXPECT_EQ(c.reading.values[2], -0.1);
  EXPECT_TRUE(c.problems.empty());
}

EstimatorConfig imuConfig() {
  return loadConfigFile(std::string(PC_EKF_SOURCE_DIR) + "/test/ros/estimator_imu.yaml");
}

sensor_msgs::Imu stamped(double t, double ay) {
  sensor_msgs::Imu msg = imuMessage(ay, 9.81, 0.0);
  msg.header.stamp = ros::Time(100.0 + t);
  return msg;
}

TEST(ImuInput, SamplesWaitForTheImuAndBadMessagesAreCountedWithoutLosingAnythingElse) {
  ImuInput input(imuConfig());
  const ros::Time t0(100.0);
  EXPECT_EQ(input.addImu(stamped(0.000, 0.0), 0.0), "");
  input.addSample(t0 + ros::Duration(0.002), suspension(1, 1), 0.0);
  EXPECT_TRUE(input.release(0.0).empty());  // waits for an IMU at or after 0.002 s
  EXPECT_EQ(input.stats().waiting, 1u);
  // Out of order (by less than the time-jump tolerance): refused, named.
  EXPECT_NE(input.addImu(stamped(-0.001, 50.0), 0.0).find("before the previous"), std::string::npos);
  // NaN in every used value of a message: refused as no_channel.
  sensor_msgs::Imu bad = stamped(0.003, kNaN);
  bad.linear_acceleration.z = kNaN;
  bad.angular_velocity.x = kNaN;
  EXPECT_NE(input.addImu(bad, 0.0).find("no usable IMU channel"), std::string::npos);
  EXPECT_TRUE(input.release(0.0).empty());
  input.addImu(stamped(0.005, 5.0), 0.0);
  std::vector<ImuReleased> out = input.release(0.0);
  ASSERT_EQ(out.size(), 1u);
  ASSERT_EQ(out[0].measurement.channels, (std::vector<int>{0, 1, 4, 5, 6}));
  EXPECT_NEAR(out[0].measurement.values[2], 2.0, 1e-12);  // 0 + 2/5 * 5
  EXPECT_EQ(input.stats().rejected.at("out_of_order"), 1u);
  EXPECT_EQ(input.stats().rejected.at("no_channel"), 1u);
  EXPECT_EQ(input.stats().problems.at("non_finite"), 3u);
  EXPECT_EQ(input.stats().samples_aligned, 1u);
  EXPECT_NEAR(input.stats().last_offset, 0.002, 1e-9);  // nearest: the reading at 0 s

  // The IMU stops: the next sample goes on without IMU channels after the
  // wait (node.road_wait_timeout 0.5 s), counted.
  input.addSample(t0 + ros::Duration(0.010), suspension(2, 2), 1.0);
  EXPECT_TRUE(input.release(1.2).empty());
  out = input.release(1.6);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].measurement.channels, (std::vector<int>{0, 1}));
  EXPECT_EQ(input.stats().samples_without_imu.at("wait_expired"), 1u);

  // It comes back 0.2 s later (more than node.imu_max_gap = 0.1 s after the
  // last): a sample in the gap is not interpolated across it.
  input.addSample(t0 + ros::Duration(0.100), suspension(3, 3), 2.0);
  input.addImu(stamped(0.205, 1.0), 2.0);
  out = input.release(2.0);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].measurement.channels.size(), 2u);
  EXPECT_EQ(input.stats().samples_without_imu.at("gap"), 1u);
}

TEST(ImuInput, ARateChangeIsCounted) {
  ImuInput input(imuConfig());
  for (int k = 0; k <= 20; ++k) input.addImu(stamped(0.005 * k, 0.0), 0.0);
  EXPECT_NEAR(input.stats().rate, 200.0, 1e-6);
  EXPECT_EQ(input.stats().rate_changes, 0u);
  const std::string problem = input.addImu(stamped(0.100 + 0.020, 0.0), 0.0);
  EXPECT_EQ(input.stats().rate_changes, 1u);
  EXPECT_NE(problem.find("rate change"), std::string::npos);
}

TEST(BagImu, WrittenAndReadBackAlignedAtTheJointStatesStamps) {
  const std::string path =
      (std::filesystem::temp_directory_path() / "pc_ekf_test_bag_imu.bag").string();
  const EstimatorConfig config = imuConfig();
  BagContents c;
  c.origin = ros::Time(1000, 0);
  c.road_contacts.t = {0.0, 0.01, 0.02, 0.03};
  c.road_contacts.heights = {{0, 0, 0, 0}, {0, 0, 0, 0}};
  c.imu = imuChannels(config.model_type->channelNames(), config.measurement.channels);
  for (int k = 1; k <= 3; ++k) {
    Measurement m = suspension(0.001 * k, 0.002 * k);
    m.time = 0.0075 * k;  // 7.5, 15, 22.5 ms
    c.samples.push_back(m);
  }
  for (int k = 0; k <= 5; ++k) {  // 2, 7, ..., 27 ms
    Measurement m;
    m.time = 0.002 + 0.005 * k;
    m.channels = {4, 5, 6};
    m.values = Eigen::Vector3d(0.1 * k, 9.81, 0.01 * k);
    c.imu_samples.push_back(m);
  }
  c.imu_variances = {0, 0, 0, 0, 1e-4, 2e-4, 3e-6};
  writeBag(path, c);
  const BagRecord r = readBag(path, bagReadOptions(config));
  EXPECT_EQ(r.imu_messages, 6);
  EXPECT_EQ(r.imu.aligned, 3);
  ASSERT_EQ(r.samples.size(), 3u);
  // 7.5 ms between 7 (k = 1) and 12 ms (k = 2): w = 0.1.
  ASSERT_EQ(r.samples[0].channels, (std::vector<int>{0, 1, 4, 5, 6}));
  EXPECT_NEAR(r.samples[0].values[2], 0.11, 1e-12);
  EXPECT_NEAR(r.samples[0].values[4], 0.011, 1e-12);
  ASSERT_EQ(r.samples[0].variances.size(), 5);
  EXPECT_NEAR(r.samples[0].variances[2], 1e-4, 1e-18);
  EXPECT_NEAR(r.samples[2].values[2], 0.1 * 4.1, 1e-12);  // 22.5 ms: between 22 and 27

  // A config without IMU channels reads the same bag without them.
  EstimatorConfig plain = config;
  plain.measurement.channels = {"u1", "u2", "v1", "v2"};
  const BagRecord p = readBag(path, bagReadOptions(plain));
  EXPECT_EQ(p.samples[0].channels, (std::vector<int>{0, 1}));

  // A bag without imu/data: samples without IMU channels, and a warning naming it.
  c.imu_samples.clear();
  writeBag(path, c);
  const BagRecord n = readBag(path, bagReadOptions(config));
  EXPECT_EQ(n.samples[0].channels, (std::vector<int>{0, 1}));
  bool named = false;
  for (const auto& w : n.warnings) named = named || w.find("no sensor_msgs/Imu") != std::string::npos;
  EXPECT_TRUE(named);
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
