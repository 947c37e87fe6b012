// The suspension readings' noise carried as states of the moving horizon
// (filter.horizon.input_noise: state, docs/method.md §4.11): what each sample
// hands the filter is the inherited covariance it had, split into the input
// slopes the states take and the rest; and on vehicle_imu.yaml's own
// one-minute drives the springs' spread covers their error over noise draws,
// where each sample's inherited covariance alone claims about twice the
// precision the draws show.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <string>

#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/io/offline_estimation.h"
#include "pc_ekf/io/road_free_stream.h"
#include "vehicle_imu_straight.h"

namespace pc_ekf {
namespace {

YAML::Node vehicleImu(double duration) {
  YAML::Node root = vehicleImuWithoutHeights();
  root["sampling"]["samples"] = static_cast<int>(200 * duration);
  root["sampling"]["duration"] = duration;
  root["filter"]["reopen"]["mode"] = "off";  // a constant load
  return root;
}

RoadFreeRecord split(const YAML::Node& root, std::uint64_t seed) {
  const EstimatorConfig c = parseConfig(root, "vehicle_imu.yaml");
  const MeasurementSeries record = synthesizeFromConfig(c, *truthOnItsRoad(c), seed);
  return roadFreeRecord(c, record, c.sampling.interval());
}

TEST(InputNoiseStates, TheSlopesCarryExactlyTheInputsPartOfTheInheritedCovariance) {
  // The same record with the travels' and rates' noise assumed negligible
  // inherits only the gyro's part: the states' slopes must account for the
  // rest.
  YAML::Node root = vehicleImu(5.0);
  root["filter"]["horizon"]["input_noise"] = "state";
  const RoadFreeRecord with = split(root, 3);
  YAML::Node quiet = YAML::Clone(root);
  for (int i = 0; i < 4; ++i) {
    quiet["measurement"]["sensor_std"][i] = 1e-12;
    quiet["measurement"]["r_relative"][i] = 0.0;
  }
  // The synthetic readings stay those of `root` (noise_relative and the
  // truth's noise floor are untouched): only what the stream assumes moves.
  const RoadFreeRecord without = split(quiet, 3);
  ASSERT_EQ(with.outputs.size(), without.outputs.size());
  int checked = 0;
  for (std::size_t k = 1; k < with.outputs.size(); k += 97) {
    const Measurement& m = with.outputs[k];
    ASSERT_EQ(m.input_slopes.rows(), m.values.size());
    ASSERT_EQ(m.input_correlation.size() * 2, m.input_slopes.cols());
    const Eigen::MatrixXd rest = m.extra_covariance - inputSlopesCovariance(m.input_slopes, m.input_correlation);
    const Eigen::MatrixXd& gyro_only = without.outputs[k].extra_covariance;
    EXPECT_LT((rest - gyro_only).cwiseAbs().maxCoeff(), 1e-9 * m.extra_covariance.cwiseAbs().maxCoeff())
        << "sample " << k;
    // The gyro (an input that is also a reading) is not carried: no slope.
    EXPECT_EQ(m.input_slopes.col(4).norm() + m.input_slopes.col(9).norm(), 0.0);
    // The blended travels' noise is shared with the sample before.
    EXPECT_GT(m.input_correlation[0], 0.7);
    EXPECT_EQ(m.input_correlation[2], 0.0);  // a rate: white
    ++checked;
  }
  EXPECT_GT(checked, 5);
}

// Over noise draws of one drive, the root mean square of the springs'
// (linear and cubic, both sides) error in their reported std.
double springsRmsError(const YAML::Node& root, int draws) {
  double sum = 0.0;
  int count = 0;
  for (int seed = 1; seed <= draws; ++seed) {
    const EstimatorConfig c = parseConfig(root, "vehicle_imu.yaml");
    const RoadFreeRecord s = split(root, static_cast<std::uint64_t>(seed));
    const OfflineResult r =
        runOfflineEstimation(c, s.outputs, s.model, EstimationMethod::kOneStep, seed);
    for (const ParameterSummary& p : r.parameters) {
      if (p.name.rfind("spring_", 0) != 0) continue;
      const double z = p.xi_mean / p.xi_stddev;  // truth: the nominal vehicle (xi 0)
      sum += z * z;
      ++count;
    }
  }
  return std::sqrt(sum / count);
}

TEST(InputNoiseStates, TheSpringsSpreadCoversTheirErrorOverNoiseDraws) {
  // Measured (8 draws of the minute): shipped 0.6-0.9; each sample's
  // inherited covariance alone (input_noise sample, no vehicle drift) 1.7-2.0.
  const YAML::Node shipped = vehicleImu(60.0);
  EXPECT_LT(springsRmsError(shipped, 8), 1.3);
  YAML::Node alone = YAML::Clone(shipped);
  alone["filter"]["horizon"]["input_noise"] = "sample";
  alone["filter"]["drift_relative"] = YAML::Node(YAML::NodeType::Sequence);
  EXPECT_GT(springsRmsError(alone, 8), 1.5);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
