// A real vehicle (docs/real_vehicle.md): data from vehicles the model does not
// describe (the nine suspension values each off by up to +-6 %, independent
// draws with fixed seeds), estimated with config/vehicle_live.yaml's settings
// and tolerances, first alone, then with the vehicle file of a calibration on
// a record with a known ballast (80 kg at 0.762 m). Loaded records: 150 kg at
// 0.62 m and 280 kg at 0.90 m. A run covers the load when M and d_CG are both
// within 3 reported std of the truth; a silent failure is a healthy miss.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>

#include "pc_ekf/io/calibration.h"
#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/io/offline_estimation.h"
#include "pc_ekf/io/tolerances.h"

namespace pc_ekf {
namespace {

const std::string kLive = std::string(PC_EKF_SOURCE_DIR) + "/config/vehicle_live.yaml";
// 6 vehicles in the suite; PC_EKF_STUDY_VEHICLES=N for the larger study of docs/studies/real_vehicle_studies.md.
int vehicles() {
  const char* n = std::getenv("PC_EKF_STUDY_VEHICLES");
  return n ? std::atoi(n) : 6;
}
const char* kNine[] = {"unsprung_mass_left",  "unsprung_mass_right",  "damping_left",
                       "damping_right",       "spring_linear_left",   "spring_linear_right",
                       "bar_inertia",         "tyre_stiffness_left", "tyre_stiffness_right"};
struct Load {
  double mass, position;
};
const Load kLoads[] = {{150.0, 0.62}, {280.0, 0.90}};
const EstimationMethod kMethods[] = {EstimationMethod::kOneStep, EstimationMethod::kEsMda};

// The vehicle's true values: vehicle_live.yaml's, each of the nine off by a
// uniform draw in [-6 %, 6 %].
std::map<std::string, double> trueVehicle(int vehicle) {
  const YAML::Node given = YAML::LoadFile(kLive)["vehicle"];
  std::mt19937_64 rng(1000 + vehicle);
  std::uniform_real_distribution<double> off(-0.06, 0.06);
  std::map<std::string, double> out;
  for (const char* name : kNine) out[name] = given[name].as<double>() * (1.0 + off(rng));
  return out;
}

// vehicle_live.yaml on the speed bump (synthetic, N = 100) with the truth's
// vehicle and readings whose noise is the R the filter assumes.
YAML::Node studyNode(int vehicle, std::uint64_t seed) {
  YAML::Node c = YAML::LoadFile(kLive);
  c["road"] = YAML::Load("{source: speed_bump}");
  c["sampling"]["samples"] = 100;
  c["pdf"]["draws"] = 1000;
  c["measurement"]["noise_relative"] = c["measurement"]["r_relative"].as<double>();
  c["truth"]["seed"] = seed;
  c["truth"]["sensor"]["noise_floor"] = c["measurement"]["sensor_std"];
  for (const auto& [name, value] : trueVehicle(vehicle)) c["truth"]["vehicle"][name] = value;
  if (std::getenv("PC_EKF_STUDY_NINE")) {  // the nine values only, +-12 %, n = 11 (Q = 156)
    YAML::Node nine(YAML::NodeType::Map);
    for (const char* name : kNine) nine[name] = 0.12;
    c["tolerances"] = nine;
    c["collocation"]["points"] = 156;
  }
  return c;
}

YAML::Node loadedNode(int vehicle, const Load& load, std::uint64_t seed) {
  YAML::Node c = studyNode(vehicle, seed);
  const double xm = (load.mass / c["uncertain"][0]["nominal"].as<double>() - 1.0) /
                    c["uncertain"][0]["relative_range"].as<double>();
  const double xd = (load.position / c["uncertain"][1]["nominal"].as<double>() - 1.0) /
                    c["uncertain"][1]["relative_range"].as<double>();
  c["truth"]["xi"] = std::vector<double>{xm, xd};
  return c;
}

// The calibration record: the ballast known, in vehicle:, nothing under uncertain:.
YAML::Node calibrationNode(int vehicle, std::uint64_t seed) {
  YAML::Node c = studyNode(vehicle, seed);
  c.remove("uncertain");
  c["filter"].remove("drift");  // the ballast does not change
  c["vehicle"]["added_mass"] = 80.0;
  c["vehicle"]["added_mass_position"] = 0.762;
  return c;
}

struct StudyRun {
  OfflineResult result;
  bool covered = false;
};

StudyRun estimate(const YAML::Node& node, const Load& load, EstimationMethod method,
             const std::string& name) {
  const EstimatorConfig c = parseConfig(node, name);
  const auto model = makeModel(c, makeRoad(c));
  const MeasurementSeries data = synthesizeFromConfig(c, *model, c.truth.seed);
  StudyRun r;
  r.result = runOfflineEstimation(c, data, model, method, c.truth.seed);
  const ParameterSummary& m = r.result.parameters[0];
  const ParameterSummary& d = r.result.parameters[1];
  EXPECT_EQ(m.name, "added_mass");
  EXPECT_EQ(d.name, "added_mass_position");
  r.covered = std::abs(m.mean - load.mass) <= 3.0 * m.stddev &&
              std::abs(d.mean - load.position) <= 3.0 * d.stddev;
  if (std::getenv("PC_EKF_STUDY_VERBOSE")) {
    std::cout << name << " " << toString(method) << " z_M " << (m.mean - load.mass) / m.stddev
              << " z_d " << (d.mean - load.position) / d.stddev << " healthy " << r.result.healthy
              << "\n";
  }
  if (!r.covered) {
    std::cout << name << " " << toString(method) << " missed: M " << m.mean << " +- " << m.stddev
              << " (truth " << load.mass << "), d_CG " << d.mean << " +- " << d.stddev << " (truth "
              << load.position << "), healthy " << r.result.healthy << "\n";
  }
  return r;
}

std::filesystem::path tempDir() {
  static const std::filesystem::path dir = [] {
    std::string pattern = (std::filesystem::temp_directory_path() / "pc_ekf_vehicle_XXXXXX").string();
    if (!mkdtemp(pattern.data())) throw std::runtime_error("mkdtemp failed");
    return std::filesystem::path(pattern);
  }();
  return dir;
}

// The vehicle file calibrate_vehicle would write for `vehicle` with `method`.
std::string calibratedFile(int vehicle, EstimationMethod method) {
  const YAML::Node node = calibrationNode(vehicle, 50 + vehicle);
  CalibrationRecord record;
  record.config = parseConfig(node, "calibration");
  record.model = makeModel(record.config, makeRoad(record.config));
  record.series = synthesizeFromConfig(record.config, *record.model, record.config.truth.seed);
  record.label = "calibration of vehicle " + std::to_string(vehicle);
  const EstimatorConfig last = record.config;
  const CalibrationResult cal = calibrate({record}, method, record.config.truth.seed);
  EXPECT_TRUE(cal.healthy) << record.label;
  std::vector<std::pair<std::string, std::string>> keys;
  for (const auto& kv : node["vehicle"]) keys.emplace_back(kv.first.Scalar(), kv.second.Scalar());
  const std::string path =
      (tempDir() / ("vehicle_" + std::to_string(vehicle) + "_" + toString(method) + ".yaml")).string();
  std::ofstream(path) << vehicleFileText(calibratedVehicleFile(cal, last, keys, {record.label}));
  return path;
}

struct Tally {
  int runs = 0, covered = 0, healthy = 0, silent = 0;
  double mass_std = 0.0;  // mean over runs
  double z2 = 0.0;        // sum of squared z-scores of M and d_CG
  void add(const StudyRun& r, const Load& load) {
    ++runs;
    covered += r.covered;
    healthy += r.result.healthy;
    silent += r.result.healthy && !r.covered;
    mass_std += r.result.parameters[0].stddev;
    const ParameterSummary &m = r.result.parameters[0], &d = r.result.parameters[1];
    z2 += std::pow((m.mean - load.mass) / m.stddev, 2) + std::pow((d.mean - load.position) / d.stddev, 2);
  }
  double zRms() const { return std::sqrt(z2 / (2.0 * runs)); }
  std::string text() const {
    return std::to_string(covered) + "/" + std::to_string(runs) + " covered, " +
           std::to_string(healthy) + " healthy, " + std::to_string(silent) + " silent, M std " +
           std::to_string(mass_std / runs) + " kg, z RMS " + std::to_string(zRms());
  }
};

// Tolerance-only runs, shared by both tests (index: method, vehicle, load).
const StudyRun& toleranceRun(int method, int vehicle, int load) {
  static std::map<std::tuple<int, int, int>, StudyRun> runs;
  const auto key = std::make_tuple(method, vehicle, load);
  if (!runs.count(key)) {
    runs[key] = estimate(loadedNode(vehicle, kLoads[load], 10 * vehicle + load + 1), kLoads[load],
                         kMethods[method], "tolerances");
  }
  return runs[key];
}

TEST(RealVehicle, TolerancesAloneCoverTheLoad) {
  for (int m = 0; m < 2; ++m) {
    Tally t;
    for (int v = 0; v < vehicles(); ++v) {
      for (int l = 0; l < 2; ++l) t.add(toleranceRun(m, v, l), kLoads[l]);
    }
    RecordProperty(toString(kMethods[m]), t.text());
    std::cout << "tolerances alone, " << toString(kMethods[m]) << ": " << t.text() << "\n";
    EXPECT_GE(t.covered, 0.9 * t.runs) << toString(kMethods[m]);
    // A calibrated std gives z-scores of RMS 1. With the prior put back after
    // re-linearisation and ES-MDA's restarts (vehicle_live.yaml): one-step
    // 0.85, ES-MDA 0.84 over 40 runs (PC_EKF_STUDY_VEHICLES=20), no healthy
    // miss; before, one-step reported a std about 25 % small (1.33) and
    // missed d_CG at 3.1 std on one healthy run (docs/studies/real_vehicle_studies.md).
    EXPECT_LT(t.zRms(), 1.25) << toString(kMethods[m]);
    EXPECT_EQ(t.silent, 0) << toString(kMethods[m]);
  }
}

TEST(RealVehicle, CalibratedVehicleFileNarrowsTheLoadAndStaysHonest) {
  for (int m = 0; m < 2; ++m) {
    Tally t, alone;
    for (int v = 0; v < vehicles(); ++v) {
      const std::string file = calibratedFile(v, kMethods[m]);
      for (int l = 0; l < 2; ++l) {
        YAML::Node node = loadedNode(v, kLoads[l], 10 * v + l + 1);
        node["vehicle_file"] = file;
        const StudyRun r = estimate(node, kLoads[l], kMethods[m], "calibrated");
        const StudyRun& base = toleranceRun(m, v, l);
        t.add(r, kLoads[l]);
        alone.add(base, kLoads[l]);
        EXPECT_TRUE(r.covered && r.result.healthy)
            << toString(kMethods[m]) << " vehicle " << v << " load " << l << ": M "
            << r.result.parameters[0].mean << " +- " << r.result.parameters[0].stddev << "; "
            << (r.result.warnings.empty() ? std::string() : r.result.warnings.front());
        EXPECT_LT(r.result.parameters[0].stddev, base.result.parameters[0].stddev);
      }
    }
    RecordProperty(toString(kMethods[m]), t.text());
    std::cout << "calibrated, " << toString(kMethods[m]) << ": " << t.text()
              << " (tolerances alone: " << alone.text() << ")\n";
    EXPECT_EQ(t.silent, 0) << toString(kMethods[m]);
    EXPECT_LT(t.zRms(), 1.25) << toString(kMethods[m]);
    EXPECT_LT(t.mass_std, 0.7 * alone.mass_std) << toString(kMethods[m]);
  }
}

// The moment-matched tolerance has the posterior's mean and std (any germ).
TEST(RealVehicle, MomentMatchedToleranceHasThePosteriorMoments) {
  for (const GermSpec& g : {GermSpec{GermFamily::kBeta, 2.0, 2.0}, GermSpec{GermFamily::kBeta, 2.0, 5.0},
                            GermSpec{GermFamily::kUniform, 0, 0}, GermSpec{GermFamily::kGamma, 3.0, 0}}) {
    const UncertainParameter u = momentMatched("k", 19400.0, 120.0, g);
    const double mean = u.nominal * (1.0 + u.relative_range * germMean(g));
    const double stddev = std::abs(u.nominal) * u.relative_range * germStddev(g);
    EXPECT_NEAR(mean, 19400.0, 1e-9) << describe(g);
    EXPECT_NEAR(stddev, 120.0, 1e-9) << describe(g);
  }
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
