// Road-free estimation on a stream (road.source none): a record is split
// into inputs and predicted readings sample by sample; each reading carries
// the variance it inherits from the noise of that sample's inputs (tare: at
// the load the samples so far weigh, renewed at 1, 2, 4, ... samples).
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <string>

#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/io/model_type.h"
#include "pc_ekf/io/road_free_stream.h"

namespace pc_ekf {
namespace {

EstimatorConfig imuConfig(int samples, double duration) {
  YAML::Node root = YAML::LoadFile(std::string(PC_EKF_SOURCE_DIR) + "/config/vehicle_imu.yaml");
  root["sampling"]["samples"] = samples;
  root["sampling"]["duration"] = duration;
  return parseConfig(root, "vehicle_imu.yaml");
}

TEST(RoadFreeStream, InheritedVarianceIsTheSamplesOwn) {
  const EstimatorConfig c = imuConfig(40, 0.2);
  const MeasurementSeries record = synthesizeFromConfig(c, *truthOnItsRoad(c), 7);
  const RoadFreeRecord split = roadFreeRecord(c, record);
  ASSERT_EQ(split.outputs.size(), record.size());
  const std::vector<std::string> inputs = RoadFreeStream::inputsFor(c, &record);
  ASSERT_EQ(inputs, (std::vector<std::string>{"u1", "u2", "v1", "v2", "gyro_x"}));
  // Outputs: accel_y accel_z gyro_x (the gyro is both: its increments are predicted).
  EXPECT_EQ(split.outputs[0].channels, (std::vector<int>{4, 5, 6}));

  // Samples 16 and 32 (the load weighed anew) against the model built on
  // the samples up to them: the sample's own variance.
  const Eigen::VectorXd abs_std = (Eigen::VectorXd(5) << 5e-4, 5e-4, 5e-3, 5e-3, 0.002).finished();
  const Eigen::VectorXd rel = (Eigen::VectorXd(5) << 0.01, 0.01, 0.01, 0.01, 0.0).finished();
  for (int k : {16, 32}) {
    std::vector<double> times;
    std::vector<std::vector<double>> columns(inputs.size());
    double accel_z = 0.0;
    for (int s = 0; s < k; ++s) {
      const Measurement& m = record[static_cast<std::size_t>(s)];
      times.push_back(m.time);
      for (std::size_t i = 0; i < inputs.size(); ++i) {
        const int ch = c.model_type->description().channelIndex(inputs[i]);
        for (std::size_t j = 0; j < m.channels.size(); ++j) {
          if (m.channels[j] == ch) columns[i].push_back(m.values[static_cast<Eigen::Index>(j)]);
        }
      }
      for (std::size_t j = 0; j < m.channels.size(); ++j) {
        if (m.channels[j] == 5) accel_z += m.values[static_cast<Eigen::Index>(j)];
      }
    }
    const auto prefix = std::make_shared<const ReadingInputs>(inputs, times, columns);
    const auto model = c.model_type->buildRoadFree(*c.modelParameters(), prefix, c.measurement.zero);
    const Eigen::VectorXd expected =
        model->inputNoiseBySample(abs_std, rel, accel_z / k)(static_cast<std::size_t>(k - 1));
    const Measurement& out = split.outputs[static_cast<std::size_t>(k - 1)];
    ASSERT_EQ(out.extra_variances.size(), 3);
    for (int j = 0; j < 3; ++j) {
      EXPECT_NEAR(out.extra_variances[j], expected[out.channels[static_cast<std::size_t>(j)]],
                  1e-12 * expected.maxCoeff())
          << "sample " << k << " output " << j;
    }
    EXPECT_GT(expected.maxCoeff(), 0.0);
  }
  // Each sample its own: the gyro's angle error grows along the record.
  EXPECT_LT(split.outputs[20].extra_variances[0], split.outputs[39].extra_variances[0]);
}

TEST(RoadFreeStream, RefusesSamplesByName) {
  const EstimatorConfig c = imuConfig(20, 0.1);
  MeasurementSeries record = synthesizeFromConfig(c, *truthOnItsRoad(c), 3);
  record[5].time = record[4].time;
  try {
    roadFreeRecord(c, record);
    FAIL() << "a repeated time was taken";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("sample 6"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("not after the last"), std::string::npos) << e.what();
  }
  // A first sample without u1: nothing to hold.
  MeasurementSeries late = synthesizeFromConfig(c, *truthOnItsRoad(c), 3);
  late[0] = onlyChannels(late[0], {1, 2, 3, 4, 5, 6});
  RoadFreeStream stream(c, RoadFreeStream::inputsFor(c));
  Measurement out;
  EXPECT_NE(stream.add(late[0], &out).find("'u1' not read yet"), std::string::npos);
  EXPECT_EQ(stream.add(late[1], &out), "");
  EXPECT_EQ(out.channels, (std::vector<int>{4, 5, 6}));
}

TEST(RoadFreeStream, NeedsAReadingToPredict) {
  YAML::Node root = YAML::LoadFile(std::string(PC_EKF_SOURCE_DIR) + "/config/vehicle_imu.yaml");
  root["measurement"]["channels"] = YAML::Load("[u1, u2, v1, v2]");
  root["measurement"]["sensor_std"] = YAML::Load("[5.0e-4, 5.0e-4, 5.0e-3, 5.0e-3]");
  root["measurement"]["r_relative"] = YAML::Load("[0.01, 0.01, 0.01, 0.01]");
  root["measurement"]["noise_relative"] = YAML::Load("[0.01, 0.01, 0.01, 0.01]");
  root["truth"]["sensor"]["noise_floor"] = YAML::Load("[5.0e-4, 5.0e-4, 5.0e-3, 5.0e-3]");
  const EstimatorConfig c = parseConfig(root, "imu.yaml");
  try {
    RoadFreeStream stream(c, RoadFreeStream::inputsFor(c));
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("needs an IMU channel"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
