// The one-step filter linearised at its mean over a moving horizon
// (filter.linearization: mean, docs/method.md §4.11) on vehicle_imu.yaml's
// own exact-model drives: a minute of driving stays healthy with every value
// within 3 reported std (the collocation filter is flagged on the same
// drive), a value the readings never see keeps its prior exactly, a load
// change is found and the new load estimated, and a model the data do not
// follow is still flagged.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/io/offline_estimation.h"
#include "pc_ekf/io/road_free_stream.h"
#include "vehicle_imu_straight.h"

namespace pc_ekf {
namespace {

YAML::Node vehicleImu(double duration, const std::string& zero) {
  YAML::Node root = vehicleImuWithoutHeights();
  root["measurement"]["zero"] = zero;
  root["sampling"]["samples"] = static_cast<int>(200 * duration);
  root["sampling"]["duration"] = duration;
  root["filter"]["linearization"] = "mean";
  // The load's re-open needs tare; the constant-load drives need none.
  root["filter"]["reopen"]["mode"] = "off";
  return root;
}

OfflineResult estimate(const YAML::Node& root, std::uint64_t seed) {
  const EstimatorConfig c = parseConfig(root, "vehicle_imu.yaml");
  const MeasurementSeries record = synthesizeFromConfig(c, *truthOnItsRoad(c), seed);
  const RoadFreeRecord split = roadFreeRecord(c, record);
  return runOfflineEstimation(c, split.outputs, split.model, EstimationMethod::kOneStep, seed);
}

// Largest |mean - truth| / std over the parameters; truth: the config's
// nominal values (truth.xi 0 and no truth.vehicle).
double worstError(const OfflineResult& r) {
  double worst = 0.0;
  for (const ParameterSummary& p : r.parameters) {
    worst = std::max(worst, std::abs(p.xi_mean) / p.xi_stddev);
  }
  return worst;
}

const ParameterSummary& named(const OfflineResult& r, const std::string& name) {
  for (const ParameterSummary& p : r.parameters) {
    if (p.name == name) return p;
  }
  throw std::invalid_argument(name);
}

TEST(MovingHorizon, AMinuteOfExactModelDrivingStaysHealthyAndCovered) {
  for (const std::string zero : {"tare", "rest"}) {
    const OfflineResult r = estimate(vehicleImu(60.0, zero), 1);
    EXPECT_TRUE(r.healthy) << zero << ": " << (r.warnings.empty() ? "" : r.warnings.front());
    EXPECT_LT(worstError(r), 3.0) << zero;
    // Unsprung masses act only through the static tilt (m_t g / k_t in the
    // tyres' compression): the exact Jacobian leaves them all but at their
    // prior (collocation's projection moves the tyres by aliasing).
    // With the nuisance values (vehicle_imu.yaml: a cross-fall and IMU
    // biases, which the static tilt shares) it moves 0.012 of its germ.
    const ParameterSummary& unsprung = named(r, "unsprung_mass_left");
    EXPECT_LT(std::abs(unsprung.xi_mean), 0.02) << zero;
    EXPECT_GT(unsprung.xi_stddev, 0.99 / std::sqrt(5.0)) << zero;
  }
}

// The mass scale (every mass, stiffness, damper rate and inertia times one
// factor) changes no reading. Ten minutes with the vehicle values walking
// ten times faster than shipped (10^-3 per sqrt(s)): linearised at the moving
// mean, the updates together inform the scale and the body mass, which does
// not walk and anchors it, is carried 1.45 std up (M +0.88); with the slope
// along the scale held at 0 it stays within 0.44 std (M -0.01).
TEST(MovingHorizon, TheMassScaleKeepsItsPrior) {
  YAML::Node root = vehicleImu(600.0, "tare");
  YAML::Node drift = root["filter"]["drift_relative"];
  for (std::size_t i = 0; i < drift.size(); ++i) {
    if (drift[i].as<double>() > 0.0) drift[i] = 1e-3;
  }
  const OfflineResult held = estimate(root, 1);
  root["filter"]["horizon"]["mass_scale_unobservable"] = false;
  const OfflineResult walked = estimate(root, 1);
  const ParameterSummary& body = named(held, "bar_mass");
  const ParameterSummary& body_walked = named(walked, "bar_mass");
  std::printf("body mass error / std: held %.2f, not held %.2f\n", body.xi_mean / body.xi_stddev,
              body_walked.xi_mean / body_walked.xi_stddev);
  EXPECT_TRUE(held.healthy);
  EXPECT_LT(std::abs(body.xi_mean) / body.xi_stddev, 1.0);
  EXPECT_LT(std::abs(named(held, "added_mass").xi_mean) / named(held, "added_mass").xi_stddev, 1.0);
  // The control: the same drive without the hold shows the walk.
  EXPECT_GT(body_walked.xi_mean / body_walked.xi_stddev, 1.0);
}

// The control: the collocation filter (the paper's linearisation) on the same
// minute without the vehicle values' walk is flagged or wrong (measured:
// unhealthy, 7.6 std). The walk changes that: at 2e-4 per sqrt(s) healthy
// and 5.1 std off (silent), at vehicle_imu.yaml's 5e-4 healthy and within 3.
TEST(MovingHorizon, TheCollocationFilterOnTheSameDriveIsFlagged) {
  YAML::Node root = vehicleImu(60.0, "tare");
  root["filter"]["linearization"] = "collocation";
  root["filter"].remove("drift_relative");
  const OfflineResult r = estimate(root, 1);
  EXPECT_TRUE(!r.healthy || worstError(r) > 3.0);
}

// Two load changes, the body settling to each as a real load does (truth
// load_change: settle): each is found once and the last load is estimated.
TEST(MovingHorizon, LoadChangesAreFoundAndTheNewLoadEstimated) {
  YAML::Node root = vehicleImu(45.0, "tare");
  root["filter"]["reopen"]["mode"] = "load";
  root["filter"]["reopen"]["after"] = 20;
  root["truth"]["load_change"] = "settle";
  root["truth"]["schedule"] = YAML::Load(
      "[{time: 15.0, values: {added_mass: 280.0, added_mass_position: 0.9}},"
      " {time: 30.0, values: {added_mass: 120.0, added_mass_position: 0.65}}]");
  const OfflineResult r = estimate(root, 2);
  EXPECT_EQ(r.reopened, 2);
  const ParameterSummary& m = named(r, "added_mass");
  const ParameterSummary& d = named(r, "added_mass_position");
  EXPECT_LT(std::abs(m.mean - 120.0), 3.0 * m.stddev) << m.mean << " +- " << m.stddev;
  EXPECT_LT(std::abs(d.mean - 0.65), 3.0 * d.stddev) << d.mean << " +- " << d.stddev;
  EXPECT_LT(m.stddev, 5.0);
  // Health and the vehicle values after changes are not yet promised: over
  // seeds 2-6, one run ends flagged and one has a spring at 3.04 std.
}

// With zero: rest the readings' zero is the start's load, which a load
// change leaves behind: refused by name.
TEST(MovingHorizon, ReopenModeLoadNeedsTare) {
  YAML::Node root = vehicleImu(2.0, "rest");
  root["filter"]["reopen"]["mode"] = "load";
  try {
    estimate(root, 1);
    FAIL() << "not refused";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("zero: tare"), std::string::npos) << e.what();
  }
}

// The IMU read up to 5 ms before or after its stamps
// (truth.timing.imu_clock_offset): the offset state finds it within its
// reported spread, the estimate stays healthy and covered, and the offset
// is reported only when configured.
TEST(MovingHorizon, ClockOffsetsOfFiveMillisecondsAreFoundAndStayCovered) {
  for (const double offset : {0.0, 0.005, -0.005}) {
    YAML::Node root = vehicleImu(30.0, "tare");
    root["truth"]["timing"]["imu_clock_offset"] = offset;
    root["filter"]["horizon"]["clock_offset"] = 0.005;
    const OfflineResult r = estimate(root, 4);
    ASSERT_TRUE(std::isfinite(r.clock_offset));
    EXPECT_LT(r.clock_offset_std, 1e-4);
    EXPECT_LT(std::abs(r.clock_offset - offset), 4.0 * r.clock_offset_std)
        << offset << ": " << r.clock_offset << " +- " << r.clock_offset_std;
    EXPECT_TRUE(r.healthy) << offset << ": " << (r.warnings.empty() ? "" : r.warnings.front());
    EXPECT_LT(worstError(r), 3.0) << offset;
  }
  YAML::Node off = vehicleImu(2.0, "tare");
  off["filter"]["horizon"]["clock_offset"] = 0.0;
  EXPECT_TRUE(std::isnan(estimate(off, 4).clock_offset));
}

TEST(MovingHorizon, AVehicleTheDataDoNotFollowIsFlagged) {
  YAML::Node root = vehicleImu(20.0, "tare");
  root["truth"]["vehicle"]["spring_linear_left"] = 19357.2 * 1.3;  // beyond its 10 %
  const OfflineResult r = estimate(root, 3);
  EXPECT_FALSE(r.healthy);
}

TEST(MovingHorizon, AModelWithDynamicStatesIsRefusedByName) {
  YAML::Node root = YAML::LoadFile(std::string(PC_EKF_SOURCE_DIR) + "/config/speed_bump.yaml");
  root["filter"]["linearization"] = "mean";
  const EstimatorConfig c = parseConfig(root, "speed_bump.yaml");
  const MeasurementSeries record = synthesizeFromConfig(c, *truthOnItsRoad(c), 1);
  try {
    runOfflineEstimation(c, record, truthOnItsRoad(c), EstimationMethod::kOneStep, 1);
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("road.source: none"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
