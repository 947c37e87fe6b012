// Road-free estimation (road.source none) on roads the estimator is never
// told, for both built-in models: the shipped configs' load estimates cover
// the truth within 3 reported std over loads, vehicles, zero conventions and
// noise seeds, none is silent (wrong and healthy), and the model errors the
// formulation can see are flagged (docs/studies/real_vehicle_studies.md, "Road-free:
// the roads and the zero"; scripts/road_free_study.py is the larger study).
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/io/offline_estimation.h"
#include "pc_ekf/io/road_free_stream.h"
#include "vehicle_imu_straight.h"

namespace pc_ekf {
namespace {

struct Load {
  double mass, x, y;  // kg; m (roll plane: y unused, x = the position from the left mount)
};

// The estimate of one synthetic drive, as estimate_offline makes it.
OfflineResult estimate(const EstimatorConfig& c, EstimationMethod method, std::uint64_t seed) {
  const MeasurementSeries record = synthesizeFromConfig(c, *truthOnItsRoad(c), seed);
  const RoadFreeRecord split = roadFreeRecord(c, record);
  return runOfflineEstimation(c, split.outputs, split.model, method, seed);
}

// The truth's germs of the load parameters: value = nominal (1 + range xi).
YAML::Node loadGerms(const YAML::Node& uncertain, const std::vector<double>& values) {
  YAML::Node xi(YAML::NodeType::Sequence);
  for (std::size_t i = 0; i < values.size(); ++i) {
    const double nominal = uncertain[i]["nominal"].as<double>();
    const double range = uncertain[i]["relative_range"].as<double>();
    xi.push_back((values[i] / nominal - 1.0) / range);
  }
  return xi;
}

// config/vehicle_imu.yaml for a vehicle without heights (vehicle_imu_straight.h; with zero: rest as its comment says);
// the truth drives `road` with `load`,
// `zero` and, when given, vehicle values that differ from the config's.
EstimatorConfig rollPlane(const std::string& road, double duration, const std::string& zero,
                          const Load& load, const std::string& vehicle) {
  YAML::Node root = vehicleImuWithoutHeights();
  root["measurement"]["zero"] = zero;
  if (zero == "rest") {  // as the config says for rest: the collocation filter, no load re-open
    root["filter"]["linearization"] = "collocation";
    root["filter"]["reopen"]["mode"] = "off";
  }
  root["sampling"]["samples"] = static_cast<int>(200 * duration);
  root["sampling"]["duration"] = duration;
  root["truth"]["road"] = YAML::Load(road);
  root["truth"]["xi"] = loadGerms(root["uncertain"], {load.mass, load.x});
  if (!vehicle.empty()) root["truth"]["vehicle"] = YAML::Load(vehicle);
  return parseConfig(root, "vehicle_imu.yaml");
}

// config/full_car_live.yaml without its road: the IMU at O (accel_z and both
// gyros; accel_y is reported not healthy road-free), vehicle_imu.yaml's noise.
EstimatorConfig fullCar(const std::string& road, const std::string& zero, const Load& load) {
  YAML::Node root =
      YAML::LoadFile(std::string(PC_EKF_SOURCE_DIR) + "/config/full_car_live.yaml");
  root["road"] = YAML::Load("{source: none}");
  root["measurement"] = YAML::Load(
      "channels: [u_fl, u_fr, u_rl, u_rr, v_fl, v_fr, v_rl, v_rr, accel_z, gyro_x, gyro_y]\n"
      "travel_blend: 0.02\n"
      "r_rule: sensor\n"
      "sensor_std: [5.0e-4, 5.0e-4, 5.0e-4, 5.0e-4, 5.0e-3, 5.0e-3, 5.0e-3, 5.0e-3, 0.03, 0.002, 0.002]\n"
      "r_relative: [0.01, 0.01, 0.01, 0.01, 0.01, 0.01, 0.01, 0.01, 0.0, 0.0, 0.0]\n"
      "noise_relative: [0.01, 0.01, 0.01, 0.01, 0.01, 0.01, 0.01, 0.01, 0.0, 0.0, 0.0]\n");
  root["measurement"]["zero"] = zero;
  root["sampling"]["samples"] = 2000;
  root["sampling"]["duration"] = 10.0;
  root["truth"]["road"] = YAML::Load(road);
  root["truth"]["xi"] = loadGerms(root["uncertain"], {load.mass, load.x, load.y});
  root["truth"]["sensor"]["noise_floor"] = YAML::Load(
      "[5.0e-4, 5.0e-4, 5.0e-4, 5.0e-4, 5.0e-3, 5.0e-3, 5.0e-3, 5.0e-3, 0.03, 0.002, 0.002]");
  return parseConfig(root, "full_car_live.yaml");
}

// The largest error of the load parameters (the first `n`), in reported std.
double worstError(const OfflineResult& r, const std::vector<double>& truth) {
  double worst = 0.0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    worst = std::max(worst, std::abs(r.parameters[i].mean - truth[i]) / r.parameters[i].stddev);
  }
  return worst;
}

struct Tally {
  int runs = 0, covered = 0, silent = 0;
  double worst = 0.0;
  void add(const OfflineResult& r, const std::vector<double>& truth) {
    const double off = worstError(r, truth);
    if (!r.healthy) {
      std::printf("  not healthy (%.2f std off): %s\n", off,
                  r.warnings.empty() ? "" : r.warnings.front().c_str());
    }
    ++runs;
    covered += off <= 3.0 && r.healthy;
    silent += off > 3.0 && r.healthy;
    worst = std::max(worst, off);
  }
};

// The paper's vehicle and one with nine values off by up to 6 %, inside
// vehicle_imu.yaml's tolerances.
const char* kOffVehicle =
    "{unsprung_mass_left: 38.4, unsprung_mass_right: 34.5, damping_left: 748.0, "
    "damping_right: 680.0, spring_linear_left: 20325.0, spring_linear_right: 18600.0, "
    "bar_inertia: 66.5, tyre_stiffness_left: 92500.0, tyre_stiffness_right: 101000.0}";

TEST(RoadFreeCoverage, RollPlaneOnRoughRoadsCoversTheLoad) {
  // ISO B at 36 km/h and ISO C at 54 km/h for 10 s; tare and rest; two
  // vehicles, two loads; one-step and ES-MDA: 32 runs, each its own seed.
  // At least 90 % covered and healthy, none silent, median std of M <= 15 kg.
  const std::vector<std::string> roads = {
      "{source: iso8608, speed_kmh: 36.0, iso8608: {class: B, seed: %d}}",
      "{source: iso8608, speed_kmh: 54.0, iso8608: {class: C, seed: %d}}"};
  const std::vector<Load> loads = {{150.0, 0.62, 0.0}, {280.0, 0.90, 0.0}};
  std::uint64_t seed = 0;
  Tally all;
  std::vector<double> m_std;
  for (EstimationMethod method : {EstimationMethod::kOneStep, EstimationMethod::kEsMda}) {
    Tally tally;
    for (const std::string& road : roads) {
      for (const char* zero : {"tare", "rest"}) {
        for (bool off : {false, true}) {
          for (const Load& load : loads) {
            ++seed;
            char text[160];
            std::snprintf(text, sizeof text, road.c_str(), static_cast<int>(seed));
            const EstimatorConfig c = rollPlane(text, 10.0, zero, load, off ? kOffVehicle : "");
            const OfflineResult r = estimate(c, method, seed);
            tally.add(r, {load.mass, load.x});
            all.add(r, {load.mass, load.x});
            m_std.push_back(r.parameters[0].stddev);
          }
        }
      }
    }
    std::printf("roll plane, %s: %d of %d covered and healthy, %d silent, worst %.2f std\n",
                toString(method).c_str(), tally.covered, tally.runs, tally.silent, tally.worst);
    EXPECT_EQ(tally.silent, 0) << toString(method);
  }
  std::sort(m_std.begin(), m_std.end());
  const double median = 0.5 * (m_std[(m_std.size() - 1) / 2] + m_std[m_std.size() / 2]);
  std::printf("roll plane: %d of %d covered and healthy; median std of M %.1f kg\n", all.covered,
              all.runs, median);
  EXPECT_GE(all.covered, 0.9 * all.runs);
  EXPECT_LE(median, 15.0);
}

TEST(RoadFreeCoverage, FullCarOnRoughRoadsCoversTheLoad) {
  // ISO B at 36 km/h and ISO C at 54 km/h for 10 s; tare and rest; two loads;
  // one-step and ES-MDA: 16 runs. M, x_M and y_M within 3 std.
  const std::vector<std::string> roads = {
      "{source: iso8608, speed_kmh: 36.0, iso8608: {class: B, seed: %d}}",
      "{source: iso8608, speed_kmh: 54.0, iso8608: {class: C, seed: %d}}"};
  const std::vector<Load> loads = {{150.0, 1.0, 0.62}, {280.0, 1.6, 0.90}};
  std::uint64_t seed = 100;
  for (EstimationMethod method : {EstimationMethod::kOneStep, EstimationMethod::kEsMda}) {
    Tally tally;
    for (const std::string& road : roads) {
      for (const char* zero : {"tare", "rest"}) {
        for (const Load& load : loads) {
          ++seed;
          char text[160];
          std::snprintf(text, sizeof text, road.c_str(), static_cast<int>(seed));
          const OfflineResult r = estimate(fullCar(text, zero, load), method, seed);
          tally.add(r, {load.mass, load.x, load.y});
        }
      }
    }
    std::printf("full car, %s: %d of %d covered and healthy, %d silent, worst %.2f std\n",
                toString(method).c_str(), tally.covered, tally.runs, tally.silent, tally.worst);
    EXPECT_EQ(tally.silent, 0) << toString(method);
    // At most two false alarms in 8. With full_car_live.yaml's body mass at 3 %
    // one-step flags 2 of these runs (6 of 8 covered and healthy; ES-MDA 8 of
    // 8): "parameter PDF mass outside the prior support", y estimated near its
    // prior's end (germ -0.85 and +0.97 for truths at -0.69 and +0.80), both
    // within 1.4 reported std of the truth. With the body mass exact it was 1
    // per method, and the bound runs - 1.
    EXPECT_GE(tally.covered, tally.runs - 2) << toString(method);
  }
}

TEST(RoadFreeCoverage, ModelErrorsAreFlagged) {
  // With tare: a left spring 25 % stiffer than its value (15 % beyond its
  // 10 % tolerance) on ISO C and on the paper bump, and the IMU 5 cm right of
  // where it is told (tolerance 2 %, 15 mm): every run not healthy. (With
  // rest on a smooth road neither shows in the readings: docs/studies/real_vehicle_studies.md.)
  const std::vector<std::pair<std::string, double>> roads = {
      {"{source: iso8608, speed_kmh: 54.0, iso8608: {class: C, seed: 3}}", 10.0},
      {"{source: speed_bump}", 3.0}};
  int runs = 0, flagged = 0;
  for (const char* error : {"{spring_linear_left: 24196.5}", "{imu_position: 0.812}"}) {
    for (const auto& [road, duration] : roads) {
      for (const Load& load : {Load{150.0, 0.62, 0.0}, Load{280.0, 0.90, 0.0}}) {
        for (EstimationMethod method : {EstimationMethod::kOneStep, EstimationMethod::kEsMda}) {
          const OfflineResult r =
              estimate(rollPlane(road, duration, "tare", load, error), method, 7);
          ++runs;
          flagged += !r.healthy;
          EXPECT_FALSE(r.healthy) << error << " " << road << " " << load.mass << " kg "
                                  << toString(method);
        }
      }
    }
  }
  std::printf("model errors: %d of %d flagged\n", flagged, runs);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
