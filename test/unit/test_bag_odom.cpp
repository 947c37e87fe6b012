// The ROS edge of speed and yaw rate: nav_msgs/Odometry on
// odom (twist.twist.linear.x -> speed) and imu/data's angular_velocity.z
// (-> gyro_z), aligned to the joint_states stamps by the IMU rule
// (filter/imu_alignment.h), in the node's input (ros/imu_input.h) and in
// bags (writeBag / readBag, as synthesize_bag and estimate_offline --bag).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include "pc_ekf/filter/measurement.h"
#include "pc_ekf/io/estimator_config.h"
#include "pc_ekf/ros/bag_io.h"
#include "pc_ekf/ros/imu_input.h"
#include "pc_ekf/ros/message_conversion.h"

namespace pc_ekf {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// The roll plane's channels: u1 u2 v1 v2 accel_y accel_z gyro_x speed gyro_z.
constexpr int kAccelY = 4, kAccelZ = 5, kGyroX = 6, kSpeed = 7, kGyroZ = 8;

// config/turns.yaml made road-free, selecting speed and gyro_z.
EstimatorConfig turnsWithSpeedAndYawRate() {
  EstimatorConfig c = loadConfigFile(std::string(PC_EKF_SOURCE_DIR) + "/config/turns.yaml");
  c.road.source = RoadSource::kNone;
  c.measurement.channels = {"u1",     "u2",     "v1",    "v2",   "accel_y",
                            "accel_z", "gyro_x", "speed", "gyro_z"};
  return c;
}

nav_msgs::Odometry odom(double t, double speed) {
  nav_msgs::Odometry msg;
  msg.header.stamp = ros::Time(100.0 + t);
  msg.twist.twist.linear.x = speed;
  return msg;
}

Measurement suspension(double t, double u1) {
  Measurement m;
  m.time = t;
  m.channels = {0, 1, 2, 3};
  m.values = Eigen::Vector4d(u1, -u1, 10 * u1, -10 * u1);
  return m;
}

TEST(OdometryConversion, SpeedVarianceAndBadInput) {
  const EstimatorConfig config = turnsWithSpeedAndYawRate();
  const int speed = odomSpeedChannel(config.model_type->channelNames(), config.measurement.channels);
  ASSERT_EQ(speed, kSpeed);
  const ImuChannels imu = imuChannels(config.model_type->channelNames(), config.measurement.channels);
  EXPECT_EQ(imu.gyro_z, kGyroZ);
  EXPECT_TRUE(imu.has(kGyroZ));
  EXPECT_FALSE(imu.has(kSpeed));
  EXPECT_EQ(odomSpeedChannel(config.model_type->channelNames(), {"u1", "u2"}), -1);

  nav_msgs::Odometry msg = odom(0.5, 13.5);
  ImuConversion c = readingFromOdometry(msg, speed);
  ASSERT_EQ(c.reading.channels, (std::vector<int>{kSpeed}));
  EXPECT_EQ(c.reading.values[0], 13.5);
  EXPECT_TRUE(std::isnan(c.reading.variances[0]));  // all zero: unknown
  EXPECT_EQ(c.unknown_covariances, 1);
  EXPECT_EQ(c.reading.stamp_ns, 100500000000LL);
  msg.twist.covariance[0] = 0.04;
  c = readingFromOdometry(msg, speed);
  EXPECT_DOUBLE_EQ(c.reading.variances[0], 0.04);
  msg.twist.covariance[0] = -2.0;
  c = readingFromOdometry(msg, speed);
  ASSERT_EQ(c.problem_kinds, (std::vector<ImuProblem>{ImuProblem::kBadCovariance}));
  EXPECT_FALSE(c.empty());
  msg.twist.covariance[0] = -1.0;
  EXPECT_TRUE(readingFromOdometry(msg, speed).empty());
  msg = odom(0.5, kNaN);
  c = readingFromOdometry(msg, speed);
  EXPECT_TRUE(c.empty());
  EXPECT_EQ(c.problem_kinds, (std::vector<ImuProblem>{ImuProblem::kNonFinite}));

  // The inverse (bags), and gyro_z through sensor_msgs/Imu both ways.
  Measurement m;
  m.channels = {kGyroX, kSpeed, kGyroZ};
  m.values = Eigen::Vector3d(0.01, 22.0, -0.3);
  const nav_msgs::Odometry back = odometryFromMeasurement(m, ros::Time(7.0), speed, 0.01);
  EXPECT_EQ(back.twist.twist.linear.x, 22.0);
  EXPECT_EQ(back.twist.covariance[0], 0.01);
  const sensor_msgs::Imu i = imuFromMeasurement(m, ros::Time(7.0), imu);
  EXPECT_EQ(i.angular_velocity.z, -0.3);
  const ImuConversion ic = readingFromImu(i, imu);
  ASSERT_EQ(ic.reading.channels, (std::vector<int>{kGyroX, kGyroZ}));
  EXPECT_EQ(ic.reading.values[1], -0.3);
}

TEST(OdomInput, SamplesWaitForTheOdometryAndGoOnWithoutItWhenItStops) {
  EstimatorConfig config = turnsWithSpeedAndYawRate();
  config.node.road_wait_timeout = 0.5;
  config.node.imu_max_gap = 0.1;
  ImuInput input(config, AlignedStream::kOdom);
  EXPECT_EQ(input.speedChannel(), kSpeed);
  EXPECT_FALSE(input.channels().any());
  const ros::Time t0(100.0);
  EXPECT_EQ(input.addOdom(odom(0.000, 10.0), 0.0), "");
  input.addSample(t0 + ros::Duration(0.004), suspension(0.004, 1e-3), 0.0);
  EXPECT_TRUE(input.release(0.0).empty());  // waits for odometry at or after 4 ms
  EXPECT_NE(input.addOdom(odom(0.005, kNaN), 0.0).find("no usable odom channel"), std::string::npos);
  input.addOdom(odom(0.010, 20.0), 0.0);
  std::vector<ImuReleased> out = input.release(0.0);
  ASSERT_EQ(out.size(), 1u);
  ASSERT_EQ(out[0].measurement.channels, (std::vector<int>{0, 1, 2, 3, kSpeed}));
  EXPECT_NEAR(out[0].measurement.values[4], 14.0, 1e-12);  // 10 + 0.4 * 10
  EXPECT_EQ(input.stats().samples_aligned, 1u);
  EXPECT_EQ(input.stats().rejected.at("no_channel"), 1u);
  EXPECT_NEAR(input.stats().last_offset, 0.004, 1e-9);

  // The odometry stops: after node.road_wait_timeout the sample goes on, counted.
  input.addSample(t0 + ros::Duration(0.020), suspension(0.020, 2e-3), 1.0);
  EXPECT_TRUE(input.release(1.2).empty());
  out = input.release(1.6);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].measurement.channels, (std::vector<int>{0, 1, 2, 3}));
  EXPECT_EQ(input.stats().samples_without_imu.at("wait_expired"), 1u);
}

// A vehicle without odometry (or odometry that starts late): the first
// samples wait node.road_wait_timeout for it as above; when none has come
// by then, a sample goes on at once; once odometry comes, samples wait again.
TEST(OdomInput, WithoutOdometrySamplesGoOnAtOnce) {
  EstimatorConfig config = turnsWithSpeedAndYawRate();
  config.node.road_wait_timeout = 0.5;
  ImuInput input(config, AlignedStream::kOdom);
  const ros::Time t0(100.0);
  for (int k = 1; k <= 3; ++k) {
    input.addSample(t0 + ros::Duration(0.005 * k), suspension(0.005 * k, 1e-3), 0.1 * k);
  }
  EXPECT_TRUE(input.release(0.4).empty());  // the first wait: odometry may be late
  std::vector<ImuReleased> out = input.release(0.6);
  ASSERT_EQ(out.size(), 3u);
  for (const ImuReleased& s : out) EXPECT_EQ(s.measurement.channels, (std::vector<int>{0, 1, 2, 3}));
  EXPECT_EQ(input.stats().samples_without_imu.at("no_message_yet"), 3u);
  input.addSample(t0 + ros::Duration(0.020), suspension(0.020, 1e-3), 0.7);
  EXPECT_EQ(input.release(0.7).size(), 1u);  // no wait of its own
  input.addOdom(odom(0.026, 10.0), 0.8);
  input.addSample(t0 + ros::Duration(0.030), suspension(0.030, 1e-3), 0.8);
  EXPECT_TRUE(input.release(0.8).empty());  // now it waits for odometry at or after 30 ms
  input.addOdom(odom(0.034, 10.0), 0.8);
  out = input.release(0.8);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].measurement.channels, (std::vector<int>{0, 1, 2, 3, kSpeed}));
}

TEST(BagOdom, SpeedAndYawRateWrittenAndReadBackAtTheJointStatesStamps) {
  const std::string path =
      (std::filesystem::temp_directory_path() / "pc_ekf_test_bag_odom.bag").string();
  const EstimatorConfig config = turnsWithSpeedAndYawRate();
  BagContents c;  // as synthesize_bag writes a road-free record: all at the sample times
  c.origin = ros::Time(1000, 0);
  c.imu = imuChannels(config.model_type->channelNames(), config.measurement.channels);
  c.odom_speed = odomSpeedChannel(config.model_type->channelNames(), config.measurement.channels);
  std::vector<double> speeds, yaw_rates;
  for (int k = 1; k <= 20; ++k) {
    const double t = 0.02 * k;
    c.samples.push_back(suspension(t, 1e-4 * k));
    Measurement imu;
    imu.time = t;
    imu.channels = {kAccelY, kAccelZ, kGyroX, kGyroZ};
    yaw_rates.push_back(0.1 * std::sin(0.3 * k) + 1e-7 * k);
    imu.values = Eigen::Vector4d(0.5 * k, 0.01 * k, 1e-3 * k, yaw_rates.back());
    c.imu_samples.push_back(imu);
    Measurement o;
    o.time = t;
    o.channels = {kSpeed};
    speeds.push_back(13.8 + 0.123456789 * k);
    o.values = Eigen::VectorXd::Constant(1, speeds.back());
    c.odom_samples.push_back(o);
  }
  writeBag(path, c);
  BagReadOptions options = bagReadOptions(config);
  EXPECT_EQ(options.odom_speed, kSpeed);
  const BagRecord r = readBag(path, options);
  EXPECT_TRUE(topicMatches(r.odom_topic, "odom"));
  EXPECT_EQ(r.odom_messages, 20);
  EXPECT_EQ(r.odom.aligned, 20);
  EXPECT_EQ(r.imu.aligned, 20);
  ASSERT_EQ(r.samples.size(), 20u);
  for (std::size_t k = 0; k < r.samples.size(); ++k) {
    const Measurement& m = r.samples[k];
    ASSERT_EQ(m.channels, (std::vector<int>{0, 1, 2, 3, kAccelY, kAccelZ, kGyroX, kSpeed, kGyroZ}));
    EXPECT_EQ(m.values[7], speeds[k]) << k;      // the reading at the very stamp, as it is
    EXPECT_EQ(m.values[8], yaw_rates[k]) << k;
    EXPECT_EQ(m.values[0], c.samples[k].values[0]);
  }

  // Odometry between the samples: interpolated at the joint_states stamps.
  for (auto& o : c.odom_samples) o.time -= 0.005;
  writeBag(path, c);
  const BagRecord s = readBag(path, options);
  EXPECT_EQ(s.odom.aligned, 19);  // the last sample: no odometry after it
  EXPECT_EQ(s.odom.no_bracket, 1);
  EXPECT_NEAR(s.samples[0].values[7], speeds[0] + 0.25 * (speeds[1] - speeds[0]), 1e-12);

  // A bag without odom: samples without the speed, and a warning naming it.
  c.odom_samples.clear();
  writeBag(path, c);
  const BagRecord n = readBag(path, options);
  EXPECT_EQ(n.samples[0].channels, (std::vector<int>{0, 1, 2, 3, kAccelY, kAccelZ, kGyroX, kGyroZ}));
  bool named = false;
  for (const auto& w : n.warnings) named = named || w.find("no nav_msgs/Odometry") != std::string::npos;
  EXPECT_TRUE(named);

  // A config without speed does not read odom.
  EstimatorConfig plain = config;
  plain.measurement.channels = {"u1", "u2", "v1", "v2"};
  EXPECT_EQ(bagReadOptions(plain).odom_speed, -1);
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
