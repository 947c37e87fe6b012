// tolerances: and vehicle_file: (docs/configuration.md): the nuisance
// parameters they make, in which order and with which nominal, and each kind of
// bad input refused with a message naming the key.
#include <gtest/gtest.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/io/estimator_config.h"
#include "pc_ekf/io/offline_estimation.h"
#include "pc_ekf/io/vehicle_file.h"
#include "pc_ekf/pc/basis_truncation.h"

namespace pc_ekf {
namespace {

const std::string kDir = std::string(PC_EKF_SOURCE_DIR) + "/config/";
#define PC_EKF_LOAD_ENTRIES                                         \
  "uncertain:\n"                                                    \
  "  - {name: added_mass, nominal: 200.0, relative_range: 0.5}\n"   \
  "  - {name: added_mass_position, nominal: 0.762, relative_range: 0.25}\n"
const char* kLoadOnly = PC_EKF_LOAD_ENTRIES;
const char* kLoad =
    "uncertain:\n"
    "  - {name: added_mass, nominal: 200.0, relative_range: 0.5}\n"
    "  - {name: added_mass_position, nominal: 0.762, relative_range: 0.25}\n"
    "pc: {order: 2}\n"
    "collocation: {points: 40}\n";

std::string errorOf(const std::string& yaml) {
  try {
    const EstimatorConfig c = parseConfigString(yaml, "bad.yaml");
    makePropagator(c, makeModel(c, makeRoad(c)));
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

double vehicleValue(const EstimatorConfig& c, const std::string& name) {
  const auto& names = c.model_type->parameterNames();
  const auto at = std::find(names.begin(), names.end(), name) - names.begin();
  return c.modelParameters()->values[at];
}

std::filesystem::path tempDir() {
  std::string pattern = (std::filesystem::temp_directory_path() / "pc_ekf_tol_XXXXXX").string();
  if (!mkdtemp(pattern.data())) throw std::runtime_error("mkdtemp failed");
  return pattern;
}

TEST(Tolerances, NuisanceParametersFollowTheLoadInTheModelsOrder) {
  const EstimatorConfig c = parseConfigString(std::string(kLoad) +
                                                  "vehicle: {spring_linear_left: 20000.0}\n"
                                                  "tolerances:\n"
                                                  "  tyre_stiffness_right: 0.1\n"
                                                  "  spring_linear_left: 0.05\n"
                                                  "  damping_left: {relative_range: 0.2, germ: {family: uniform}}\n"
                                                  "  bar_length: 0\n",
                                              "t.yaml");
  ASSERT_EQ(c.uncertain.size(), 5u);  // bar_length: 0 leaves it fixed
  EXPECT_EQ(c.loadCount(), 2);
  EXPECT_EQ(c.tolerance_count, 3);
  EXPECT_EQ(c.uncertain[0].name, "added_mass");
  EXPECT_EQ(c.uncertain[2].name, "damping_left");  // model order, not the file's
  EXPECT_EQ(c.uncertain[3].name, "spring_linear_left");
  EXPECT_EQ(c.uncertain[4].name, "tyre_stiffness_right");
  EXPECT_DOUBLE_EQ(c.uncertain[3].nominal, 20000.0);  // the vehicle's value
  EXPECT_DOUBLE_EQ(c.uncertain[3].relative_range, 0.05);
  EXPECT_EQ(c.uncertain[3].germ.family, GermFamily::kBeta);
  EXPECT_DOUBLE_EQ(c.uncertain[3].germ.alpha, 2.0);
  EXPECT_EQ(c.uncertain[2].germ.family, GermFamily::kUniform);
  EXPECT_EQ(c.truth.xi.size(), 5u);  // tolerances' truth: the vehicle (xi 0)
  EXPECT_DOUBLE_EQ(c.truth.xi[3], 0.0);
}

TEST(Tolerances, TruthVehicleMayLieOutsideTheTolerance) {
  const EstimatorConfig c = parseConfigString(std::string(kLoad) +
                                                  "tolerances: {spring_linear_left: 0.1}\n"
                                                  "truth: {xi: [0.2, -0.3], vehicle: {spring_linear_left: 23228.64}}\n",
                                              "t.yaml");
  ASSERT_EQ(c.truth.xi.size(), 3u);
  EXPECT_NEAR(c.truth.xi[2], (23228.64 / 19357.2 - 1.0) / 0.1, 1e-12);  // 2: outside [-1, 1]
  const auto model = makeModel(c, makeRoad(c));
  EXPECT_DOUBLE_EQ(truthParameters(c, *model)[model->parameterIndex("spring_linear_left")],
                   19357.2 * (1.0 + 0.1 * c.truth.xi[2]));
}

TEST(Tolerances, DriftPerLoadParameterLeavesTheVehicleFixed) {
  const EstimatorConfig c = parseConfigString(std::string(kLoad) +
                                                  "tolerances: {bar_inertia: 0.15}\n"
                                                  "filter: {drift: [2.0, 0.0]}\n",
                                              "t.yaml");
  EXPECT_EQ(c.safeguards.drift, Eigen::Vector3d(2.0, 0.0, 0.0));
}

TEST(Tolerances, BadInputNamesTheKey) {
  EXPECT_NE(errorOf(std::string(kLoad) + "tolerances: {spring_rate: 0.1}\n")
                .find("'tolerances.spring_rate': unknown key"),
            std::string::npos);
  EXPECT_NE(errorOf(std::string(kLoad) + "tolerances: {spring_rate: 0.1}\n").find("spring_linear_left"),
            std::string::npos);  // the model's names are listed
  EXPECT_NE(errorOf(std::string(kLoad) + "tolerances: {added_mass: 0.1}\n").find("under uncertain:"),
            std::string::npos);
  EXPECT_NE(errorOf(std::string(kLoad) + "tolerances: {damping_left: -0.1}\n")
                .find("tolerances.damping_left"),
            std::string::npos);
  // A mass may not reach zero: the tolerance's end is outside the model's domain.
  EXPECT_NE(errorOf(std::string(kLoad) + "tolerances: {unsprung_mass_left: 1.2}\n")
                .find("'tolerances.unsprung_mass_left'"),
            std::string::npos);
  EXPECT_EQ(errorOf(std::string(kLoad) + "tolerances: {unsprung_mass_left: 0.5}\n"), "");
  // Without uncertain: a tolerance alone is a valid config (calibration).
  EXPECT_EQ(errorOf("tolerances: {bar_inertia: 0.15}\npc: {order: 2}\n"), "");
  EXPECT_NE(errorOf("tolerances: {bar_inertia: 0}\n").find("'tolerances'"), std::string::npos);
}

TEST(Tolerances, TensorGaussRuleRefusedForManyParameters) {
  const std::string e = errorOf(std::string(kLoadOnly) +
                                "tolerances: {damping_left: 0.2, damping_right: 0.2, "
                                "spring_linear_left: 0.1, spring_linear_right: 0.1, bar_inertia: 0.1}\n"
                                "collocation: {sequence: gauss, points: 5}\n");
  EXPECT_NE(e.find("'collocation.sequence'"), std::string::npos) << e;
  EXPECT_NE(e.find("5^7 = 78125"), std::string::npos) << e;
}

TEST(VehicleFile, MergedRelativeToTheConfigTheFileWins) {
  const auto dir = tempDir();
  std::filesystem::create_directories(dir / "vehicles");
  std::ofstream(dir / "vehicles" / "car.yaml")
      << "vehicle: {spring_linear_left: 20100.5, bar_mass: 600}\n"
         "tolerances: {spring_linear_left: {relative_range: 0.01}}\n";
  std::ofstream(dir / "live.yaml") << kLoad
                                   << "vehicle_file: vehicles/car.yaml\n"
                                      "vehicle: {bar_mass: 590, bar_inertia: 60}\n"
                                      "tolerances: {spring_linear_left: 0.1, bar_inertia: 0.15}\n";
  const EstimatorConfig c = loadConfigFile((dir / "live.yaml").string());
  EXPECT_EQ(c.vehicle_file, (dir / "vehicles" / "car.yaml").string());
  EXPECT_DOUBLE_EQ(vehicleValue(c, "bar_mass"), 600.0);   // the file's
  EXPECT_DOUBLE_EQ(vehicleValue(c, "bar_inertia"), 60.0);  // the config's (not in the file)
  ASSERT_EQ(c.tolerance_count, 2);
  EXPECT_EQ(c.uncertain[2].name, "spring_linear_left");
  EXPECT_DOUBLE_EQ(c.uncertain[2].relative_range, 0.01);  // the file's
  EXPECT_DOUBLE_EQ(c.uncertain[2].nominal, 20100.5);
  EXPECT_DOUBLE_EQ(c.uncertain[3].relative_range, 0.15);  // the config's
  std::filesystem::remove_all(dir);
}

// configFileHash (estimate_offline --config-hash, estimate_fleet's rows): the
// vehicle file's contents count, not its name or where they are written.
TEST(VehicleFile, ConfigHashCoversTheFileContents) {
  const auto dir = tempDir();
  std::ofstream(dir / "a.yaml") << "vehicle: {bar_mass: 600}\n";
  std::ofstream(dir / "b.yaml") << "vehicle: {bar_mass: 600}\n";
  std::ofstream(dir / "c.yaml") << "vehicle: {bar_mass: 601}\n";
  std::ofstream(dir / "via_a.yaml") << kLoad << "vehicle_file: a.yaml\n";
  std::ofstream(dir / "via_b.yaml") << kLoad << "vehicle_file: b.yaml\n";
  std::ofstream(dir / "via_c.yaml") << kLoad << "vehicle_file: c.yaml\n";
  std::ofstream(dir / "inline.yaml") << kLoad << "vehicle: {bar_mass: 600}\n";
  const auto hash = [&](const char* name) { return configFileHash((dir / name).string()); };
  EXPECT_EQ(hash("via_a.yaml"), hash("via_b.yaml"));
  EXPECT_EQ(hash("via_a.yaml"), hash("inline.yaml"));
  EXPECT_NE(hash("via_a.yaml"), hash("via_c.yaml"));
  std::ofstream(dir / "bad.yaml") << kLoad << "vehicle: {bar_mass: -3}\n";
  EXPECT_THROW(hash("bad.yaml"), ConfigError);  // checked like loadConfigFile
  std::filesystem::remove_all(dir);
}

TEST(VehicleFile, BadFilesAreNamed) {
  const auto dir = tempDir();
  const auto load = [&](const std::string& file_text, const std::string& key) {
    std::ofstream(dir / "v.yaml") << file_text;
    std::ofstream(dir / "c.yaml") << kLoad << "vehicle_file: " << key << "\n";
    try {
      loadConfigFile((dir / "c.yaml").string());
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(load("vehicle: {}\n", "missing.yaml").find("cannot open"), std::string::npos);
  EXPECT_NE(load("vehicle: {}\npc: {order: 2}\n", "v.yaml").find("only vehicle: and tolerances:"),
            std::string::npos);
  EXPECT_NE(load("vehicle: {bar_mass: -3}\n", "v.yaml").find("vehicle.bar_mass"), std::string::npos);
  EXPECT_NE(load("vehicle: [1, 2\n", "v.yaml").find("not valid YAML"), std::string::npos);
  EXPECT_EQ(load("vehicle: {bar_mass: 600}\n", "v.yaml"), "");
  std::filesystem::remove_all(dir);
}

// What calibrate_vehicle writes reads back as the same values and tolerances.
TEST(VehicleFile, WrittenFileReadsBackExactly) {
  VehicleFile f;
  f.header = {"test"};
  f.vehicle = {{"bar_mass", roundTripText(580.123456789012)}, {"spring_linear_left", roundTripText(0.1 + 0.2)}};
  f.tolerances = {{"spring_linear_left", 0.1 + 0.2, 1.0 / 3.0, GermSpec{}},
                  {"bar_mass", 580.0, 0.01, GermSpec{GermFamily::kBeta, 2.0, 5.0}}};
  const auto dir = tempDir();
  std::ofstream(dir / "v.yaml") << vehicleFileText(f);
  std::ofstream(dir / "c.yaml") << kLoad << "vehicle_file: v.yaml\n";
  const EstimatorConfig c = loadConfigFile((dir / "c.yaml").string());
  EXPECT_EQ(vehicleValue(c, "bar_mass"), 580.123456789012);
  ASSERT_EQ(c.tolerance_count, 2);
  EXPECT_EQ(c.uncertain[2].name, "bar_mass");
  EXPECT_EQ(c.uncertain[2].nominal, 580.0);  // differs from the value: written
  EXPECT_EQ(c.uncertain[2].germ.beta, 5.0);
  EXPECT_EQ(c.uncertain[3].nominal, 0.1 + 0.2);
  EXPECT_EQ(c.uncertain[3].relative_range, 1.0 / 3.0);
  std::filesystem::remove_all(dir);
}

// Every vehicle value the readings depend on has a tolerance (the IMU's mount
// only where an IMU channel is read; a height or bar left at 0 is not there;
// road-free, the mount plane's height and the wheel radius enter only the
// rollover outputs: the travels carry the links' forces).
TEST(VehicleLive, ToleranceOnEveryVehicleValue) {
  for (const char* file : {"vehicle_live.yaml", "vehicle_imu.yaml"}) {
  const EstimatorConfig c = loadConfigFile(kDir + file);
  const bool imu = c.measurement.readings(c.model_type->description()).as_states;
  for (const auto& name : c.model_type->parameterNames()) {
    if (name == "gravity" || name == "added_mass" || name == "added_mass_position") continue;
    if (name == "imu_position" && !imu) continue;
    if (vehicleValue(c, name) == 0.0) continue;  // heights and bar left out: not modelled
    if ((name == "mount_height" || name == "wheel_radius") && c.road.source == RoadSource::kNone) {
      continue;
    }
    bool listed = false;
    for (int i = c.loadCount(); i < static_cast<int>(c.uncertain.size()); ++i) {
      listed = listed || c.uncertain[i].name == name;
    }
    EXPECT_TRUE(listed) << file << ": " << name;
  }
  EXPECT_EQ(c.loadCount(), std::string(file) == "vehicle_imu.yaml" ? 3 : 2);  // and h_M
  }
}

// vehicle_live.yaml: the one-step filter on the basis without tolerance
// products (S = 58, Q = 116), the batch methods on total degree (S = 136,
// Q = 306): ES-MDA gives, to the last bit, what it gives with total degree
// and Q = 306 for both, and the one-step filter's coefficients have 58 terms.
TEST(BatchDesign, EsMdaOnItsOwnDesignOneStepOnTheSparseBasis) {
  YAML::Node split = YAML::LoadFile(kDir + "vehicle_live.yaml");
  split["road"] = YAML::Load("{source: speed_bump}");
  split["sampling"] = YAML::Load("{samples: 12, duration: 0.36}");
  split["pdf"]["draws"] = 200;
  YAML::Node full = YAML::Clone(split);
  full["pc"].remove("batch_tolerance_interactions");
  full["pc"]["tolerance_interactions"] = true;
  full["collocation"].remove("batch_points");
  full["collocation"]["points"] = 306;

  const EstimatorConfig a = parseConfig(split, "split.yaml");
  const EstimatorConfig b = parseConfig(full, "full.yaml");
  ASSERT_EQ(a.uncertain.size(), 15u);
  EXPECT_EQ(truncatedMultiIndices(15, 2, a.pc_truncation).size(), 58u);
  EXPECT_EQ(truncatedMultiIndices(15, 2, a.batchTruncation()).size(), 136u);
  EXPECT_EQ(a.collocation.points, 116);
  EXPECT_EQ(a.collocation.batchPoints(), 306);
  EXPECT_TRUE(separateBatchDesign(a));
  EXPECT_FALSE(separateBatchDesign(b));
  // Unset, the batch design follows the one-step filter's, also when a
  // program changes it after parsing.
  EstimatorConfig d = b;
  d.collocation.points = 200;
  d.pc_truncation.single_from = 2;
  EXPECT_EQ(batchDesignConfig(d).collocation.points, 200);
  EXPECT_EQ(batchDesignConfig(d).pc_truncation.single_from, 2);
  EXPECT_FALSE(separateBatchDesign(d));

  const auto model = makeModel(a, makeRoad(a));
  const MeasurementSeries data = synthesizeFromConfig(a, *model, 3);
  const OfflineResult ea = runOfflineEstimation(a, data, model, EstimationMethod::kEsMda, 3);
  const OfflineResult eb = runOfflineEstimation(b, data, model, EstimationMethod::kEsMda, 3);
  ASSERT_EQ(ea.parameters.size(), eb.parameters.size());
  for (std::size_t i = 0; i < ea.parameters.size(); ++i) {
    EXPECT_EQ(ea.parameters[i].mean, eb.parameters[i].mean) << ea.parameters[i].name;
    EXPECT_EQ(ea.parameters[i].stddev, eb.parameters[i].stddev) << ea.parameters[i].name;
  }
  EXPECT_EQ(ea.last_record.coefficients.cols(), 136);
  const OfflineResult oa = runOfflineEstimation(a, data, model, EstimationMethod::kOneStep, 3);
  EXPECT_EQ(oa.last_record.coefficients.cols(), 58);
}

TEST(BatchDesign, TooFewBatchPointsAreRefusedByName) {
  // n = 5, p = 2: total degree S = 21; one tolerance germ per term: S = 6 + 3 * 4 = 18.
  const std::string sparse = "pc: {order: 2, tolerance_interactions: false, "
                             "batch_tolerance_interactions: true}\n";
  const std::string base = std::string(PC_EKF_LOAD_ENTRIES) +
                           "tolerances: {spring_linear_left: 0.1, spring_linear_right: 0.1, "
                           "damping_left: 0.2}\n" + sparse;
  EXPECT_NE(errorOf(base + "collocation: {points: 36, batch_points: 20}\n")
                .find("collocation.batch_points"),
            std::string::npos);
  EXPECT_EQ(errorOf(base + "collocation: {points: 36, batch_points: 21}\n"), "");
  EXPECT_EQ(errorOf(base + "collocation: {points: 18, batch_points: 42}\n"), "");
  EXPECT_NE(errorOf(base + "collocation: {points: 17, batch_points: 42}\n")
                .find("collocation.points"),
            std::string::npos);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
