// Synthetic data whose truth differs from the estimator's model (truth.vehicle,
// truth.sensor, truth.timing, truth.schedule, road course): the defaults give
// the old data bit for bit, each feature does exactly what it says, and bad
// keys are refused by name.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "pc_ekf/filter/trajectory_simulation.h"
#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/io/offline_estimation.h"
#include "pc_ekf/model/roll_plane_model.h"

namespace pc_ekf {
namespace {

const std::string kDir = std::string(PC_EKF_SOURCE_DIR) + "/config/";

// Speed bump, 20 samples over 3 s; `truth` and `extra` are inserted as YAML.
EstimatorConfig bumpConfig(const std::string& truth, const std::string& extra = "",
                           int samples = 20, double duration = 3.0) {
  const std::string yaml =
      "uncertain:\n"
      "  - {name: added_mass, nominal: 200.0, relative_range: 0.5}\n"
      "  - {name: added_mass_position, nominal: 0.762, relative_range: 0.25}\n"
      "sampling: {samples: " + std::to_string(samples) + ", duration: " +
      std::to_string(duration) + "}\n"
      "integration: {method: dp5, max_step: 0.003}\n"
      "truth: {xi: [0.2326, -0.3875]" + (truth.empty() ? "" : ", " + truth) + "}\n" + extra;
  return parseConfigString(yaml, "test.yaml");
}

std::string errorOf(const std::string& truth, const std::string& extra = "") {
  try {
    bumpConfig(truth, extra);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

struct Case {
  EstimatorConfig c;
  std::shared_ptr<const RoadInput> road;
  std::shared_ptr<const MechanicalModel> model;
  explicit Case(EstimatorConfig config) : c(std::move(config)) {
    road = std::dynamic_pointer_cast<const RoadInput>(makeRoad(c));
    model = makeModel(c, road);
  }
  MeasurementSeries data(std::uint64_t seed = 1) const {
    return synthesizeFromConfig(c, *model, seed);
  }
  // Noise-free values of the same samples.
  MeasurementSeries clean(std::uint64_t seed = 1) const {
    const auto truth = truthModel(c, *model);
    MeasurementSeries out;
    synthesizeMeasurements(*truth, truthParameters(c, *model), syntheticSettings(c, *truth, seed),
                           &out);
    return out;
  }
};

// The synthesis as it was before the truth features (verbatim semantics).
MeasurementSeries oldSynthesis(const EstimatorConfig& c, const MechanicalModel& model,
                               std::uint64_t seed) {
  const ParameterMapping mapping(model, c.uncertain);
  const Eigen::VectorXd xi = Eigen::Map<const Eigen::VectorXd>(c.truth.xi.data(), c.truth.xi.size());
  const Eigen::VectorXd truth = mapping.fullParameters(c.parameterValues(xi));
  const std::vector<double> times = uniformSampleTimes(c.sampling.samples, c.sampling.duration);
  const std::vector<int> channels = channelIndices(c);
  const auto z = simulateChannels(model, truth, times, c.integration);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  MeasurementSeries out;
  for (std::size_t k = 0; k < times.size(); ++k) {
    Measurement m;
    m.time = times[k];
    m.channels = channels;
    m.values.resize(channels.size());
    for (std::size_t j = 0; j < channels.size(); ++j) {
      const double v = z[k](channels[j], 0);
      m.values[j] = v + std::hypot(c.measurement.noise_relative * v, c.measurement.noise_floor) *
                            normal(rng);
    }
    out.push_back(m);
  }
  return out;
}

void expectIdentical(const MeasurementSeries& a, const MeasurementSeries& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].time, b[k].time) << k;
    ASSERT_EQ(a[k].channels, b[k].channels) << k;
    for (Eigen::Index j = 0; j < a[k].values.size(); ++j) {
      EXPECT_EQ(a[k].values[j], b[k].values[j]) << "sample " << k << " channel " << j;
    }
  }
}

double maxDifference(const MeasurementSeries& a, const MeasurementSeries& b) {
  double d = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    d = std::max(d, (a[k].values - b[k].values).cwiseAbs().maxCoeff());
  }
  return d;
}

// ---------------------------------------------------------------- defaults

TEST(SyntheticTruth, ShippedConfigsGiveTheOldDataBitForBit) {
  for (const char* name : {"speed_bump.yaml", "sine_1hz.yaml", "sine_1hz_linear.yaml"}) {
    const Case s(loadConfigFile(kDir + name));
    EXPECT_FALSE(s.c.truth.model) << name;
    EXPECT_TRUE(s.c.truth.sensor.bias.empty() && s.c.truth.sensor.noise_floor.empty() &&
                s.c.truth.sensor.quantisation.empty())
        << name;
    EXPECT_FALSE(s.c.truth.timing.active()) << name;
    EXPECT_TRUE(s.c.truth.schedule.empty()) << name;
    for (std::uint64_t seed : {1u, 5u}) {
      SCOPED_TRACE(std::string(name) + " seed " + std::to_string(seed));
      expectIdentical(s.data(seed), oldSynthesis(s.c, *s.model, seed));
    }
  }
}

TEST(SyntheticTruth, ExplicitDefaultValuesGiveTheOldData) {
  const Case s(bumpConfig(
      "vehicle: {}, sensor: {noise_floor: [], bias: [], quantisation: []}, "
      "timing: {jitter: 0, stamp_error: 0, drop_fraction: 0, seed: 9}, schedule: []",
      "measurement: {noise_floor: 1.0e-4}\n"));
  expectIdentical(s.data(3), oldSynthesis(s.c, *s.model, 3));
}

// ---------------------------------------------------------------- truth.vehicle

TEST(SyntheticTruth, VehicleOverrideEqualsAModelOfTheOverriddenVehicle) {
  const Case plain(bumpConfig(""));
  const Case over(bumpConfig("vehicle: {spring_linear_left: 20325.06}"));
  // The estimator keeps the vehicle section.
  EXPECT_EQ(dynamic_cast<const RollPlaneModel&>(*over.model).nominal().spring_linear[0], 19357.2);
  ASSERT_TRUE(over.c.truth.model);
  EXPECT_EQ(VehicleParameters::from(*over.c.truth.model).spring_linear[0], 20325.06);
  EXPECT_EQ(VehicleParameters::from(*over.c.truth.model).spring_linear[1], 19357.2);

  VehicleParameters v = VehicleParameters::from(*over.c.model);
  v.spring_linear[0] = 20325.06;
  const RollPlaneModel reference(v, over.road);
  const ParameterMapping mapping(reference, over.c.uncertain);
  const Eigen::VectorXd xi = Eigen::Map<const Eigen::VectorXd>(over.c.truth.xi.data(), 2);
  const Eigen::VectorXd params = mapping.fullParameters(over.c.parameterValues(xi));
  EXPECT_EQ(truthParameters(over.c, *over.model), params);
  SyntheticDataSettings settings;
  settings.times = uniformSampleTimes(20, 3.0);
  settings.channels = {0, 1, 2, 3};
  settings.noise_relative = 0.01;
  settings.seed = 1;
  settings.integration = over.c.integration;
  const MeasurementSeries data = over.data(1);
  expectIdentical(data, synthesizeMeasurements(reference, params, settings));
  // 5 % stiffer left spring: the left deflection changes by millimetres.
  EXPECT_GT(maxDifference(data, plain.data(1)), 1e-4);
}

TEST(SyntheticTruth, DamperLawOverrideChangesTheData) {
  const Case plain(bumpConfig(""));
  const Case linear(bumpConfig("vehicle: {damper: linear}"));
  EXPECT_EQ(dynamic_cast<const RollPlaneModel&>(*linear.model).nominal().damper, DamperLaw::kTanh);
  EXPECT_GT(maxDifference(linear.data(), plain.data()), 1e-3);
}

// ---------------------------------------------------------------- truth.sensor

TEST(SyntheticTruth, BiasAndQuantisationAreExact) {
  const Case s(bumpConfig(
      "sensor: {bias: [0.001, -0.002, 0.01, 0.0], quantisation: [0.001, 0, 0.005, 0.002]}",
      "measurement: {noise_relative: 0.0, noise_floor: 0.0}\n"));
  const MeasurementSeries data = s.data(), clean = s.clean();
  const double bias[4] = {0.001, -0.002, 0.01, 0.0}, step[4] = {0.001, 0.0, 0.005, 0.002};
  ASSERT_EQ(data.size(), 20u);
  int changed = 0;
  for (std::size_t k = 0; k < data.size(); ++k) {
    for (int j = 0; j < 4; ++j) {
      const double z = clean[k].values[j] + bias[j];
      const double want = step[j] > 0.0 ? step[j] * std::round(z / step[j]) : z;
      EXPECT_EQ(data[k].values[j], want) << k << " " << j;
      if (step[j] > 0.0) {
        EXPECT_NEAR(data[k].values[j] / step[j], std::round(data[k].values[j] / step[j]), 1e-9);
      }
      changed += data[k].values[j] != clean[k].values[j];
    }
  }
  EXPECT_GT(changed, 60);
  EXPECT_EQ(data[5].values[1], clean[5].values[1] - 0.002);
}

TEST(SyntheticTruth, SensorNoiseFloorReplacesTheMeasurementFloor) {
  const std::string m = "measurement: {noise_relative: 0.0, noise_floor: 1.0e-3}\n";
  const Case a(bumpConfig("", m));
  const Case b(bumpConfig("sensor: {noise_floor: [2.0e-3, 2.0e-3, 4.0e-3, 1.0e-3]}", m));
  const Case scalar(bumpConfig("sensor: {noise_floor: 2.0e-3}", m));
  const Case list(bumpConfig("sensor: {noise_floor: [2.0e-3, 2.0e-3, 2.0e-3, 2.0e-3]}", m));
  expectIdentical(scalar.data(), list.data());
  const MeasurementSeries da = a.data(), db = b.data(), z = a.clean();
  const double factor[4] = {2.0, 2.0, 4.0, 1.0};
  for (std::size_t k = 0; k < z.size(); ++k) {
    for (int j = 0; j < 4; ++j) {
      const double ea = da[k].values[j] - z[k].values[j], eb = db[k].values[j] - z[k].values[j];
      EXPECT_NEAR(eb, factor[j] * ea, 1e-15) << k << " " << j;
    }
  }
}

// ---------------------------------------------------------------- truth.timing

TEST(SyntheticTruth, DropFractionHalfDropsHalfTheSamples) {
  const Case s(bumpConfig("timing: {drop_fraction: 0.5, seed: 4}", "", 2000, 60.0));
  const MeasurementSeries data = s.data();
  // Binomial(2000, 0.5): 1000 +- 4 sigma, sigma = 22.4.
  EXPECT_NEAR(static_cast<double>(data.size()), 1000.0, 4.0 * std::sqrt(500.0));
  // Kept samples keep their nominal stamps, in order.
  const std::vector<double> t = uniformSampleTimes(2000, 60.0);
  std::size_t k = 0;
  for (const auto& m : data) {
    while (k < t.size() && t[k] != m.time) ++k;
    ASSERT_LT(k, t.size()) << "stamp " << m.time << " is no nominal time";
  }
  // Another timing seed drops other samples.
  const Case other(bumpConfig("timing: {drop_fraction: 0.5, seed: 5}", "", 2000, 60.0));
  EXPECT_NE(sampleTimes(other.data()), sampleTimes(data));
}

TEST(SyntheticTruth, JitterKeepsTimesIncreasingWithTheGivenStd) {
  const double dt = 0.03, jitter = 0.003;
  const Case s(bumpConfig("timing: {jitter: 0.003}", "", 2000, 60.0));
  const MeasurementSeries data = s.data();
  ASSERT_EQ(data.size(), 2000u);
  const std::vector<double> t = uniformSampleTimes(2000, 60.0);
  double sum = 0.0, sum2 = 0.0;
  for (std::size_t k = 0; k < data.size(); ++k) {
    ASSERT_GT(data[k].time, k == 0 ? 0.0 : data[k - 1].time) << k;
    const double d = data[k].time - t[k];
    sum += d;
    sum2 += d * d;
  }
  const double mean = sum / 2000.0, sd = std::sqrt(sum2 / 2000.0 - mean * mean);
  EXPECT_NEAR(mean, 0.0, 4.0 * jitter / std::sqrt(2000.0));
  EXPECT_NEAR(sd, jitter, 4.0 * jitter / std::sqrt(2.0 * 2000.0));
  // A jitter larger than the interval is clipped to +-0.45 dt: still increasing.
  const Case wild(bumpConfig("timing: {jitter: 0.1}", "", 200, 6.0));
  const MeasurementSeries w = wild.data();
  for (std::size_t k = 0; k < w.size(); ++k) {
    ASSERT_GT(w[k].time, k == 0 ? 0.0 : w[k - 1].time) << k;
    EXPECT_LE(std::abs(w[k].time - (k + 1) * dt), 0.45 * dt + 1e-12) << k;
  }
}

TEST(SyntheticTruth, TimingUsesItsOwnGeneratorSoTheNoiseDrawsStay) {
  const std::string m = "measurement: {noise_relative: 0.0, noise_floor: 1.0e-3}\n";
  const Case plain(bumpConfig("", m));
  const Case jittered(bumpConfig("timing: {jitter: 0.01}", m));
  const MeasurementSeries a = plain.data(), za = plain.clean(), b = jittered.data(),
                          zb = jittered.clean();
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_NE(a[k].time, b[k].time);
    for (int j = 0; j < 4; ++j) {
      EXPECT_NEAR(b[k].values[j] - zb[k].values[j], a[k].values[j] - za[k].values[j], 1e-15);
    }
  }
}

TEST(SyntheticTruth, StampErrorMovesStampsButNotTheReadings) {
  const Case plain(bumpConfig("", "", 400, 12.0));
  const Case off(bumpConfig("timing: {stamp_error: 0.002}", "", 400, 12.0));
  const MeasurementSeries a = plain.data(), b = off.data();
  ASSERT_EQ(a.size(), b.size());
  double sum2 = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].values, b[k].values) << k;  // read at the nominal instants
    sum2 += (b[k].time - a[k].time) * (b[k].time - a[k].time);
    if (k > 0) {
      ASSERT_GT(b[k].time, b[k - 1].time);
    }
  }
  EXPECT_NEAR(std::sqrt(sum2 / 400.0), 0.002, 4.0 * 0.002 / std::sqrt(800.0));
}

TEST(SyntheticTruth, SampleTimesOfTheDataDoNotDependOnTheNoiseSeed) {
  const Case s(bumpConfig("timing: {jitter: 0.01, drop_fraction: 0.3, seed: 2}", "", 50, 5.0));
  const std::vector<double> times = syntheticSampleTimes(s.c);
  EXPECT_LT(times.size(), 50u);
  EXPECT_EQ(sampleTimes(s.data(1)), times);
  EXPECT_EQ(sampleTimes(s.data(8)), times);
  EXPECT_EQ(syntheticSampleTimes(bumpConfig("")), uniformSampleTimes(20, 3.0));
}

TEST(SyntheticTruth, NoSampleLeftIsRefusedByTheEstimation) {
  const Case s(bumpConfig("timing: {drop_fraction: 0.999}", "", 3, 3.0));
  const MeasurementSeries data = s.data();
  ASSERT_TRUE(data.empty());
  EXPECT_THROW(runOfflineEstimation(s.c, data, s.model, EstimationMethod::kOneStep, 1),
               std::invalid_argument);
}

// ---------------------------------------------------------------- truth.schedule

TEST(SyntheticTruth, ScheduleCarriesTheStateOverAndContinuesWithTheNewParameters) {
  const std::string m = "measurement: {noise_relative: 0.0}\n";
  const double change = 0.5;  // on the bump, between samples 0.45 and 0.6 s
  const Case plain(bumpConfig("", m));
  const Case sched(bumpConfig("schedule: [{time: 0.5, values: {added_mass: 263.26}}]", m));
  const MeasurementSeries a = plain.data(), b = sched.data();
  ASSERT_EQ(a.size(), 20u);
  ASSERT_EQ(b.size(), 20u);

  EXPECT_NEAR(truthXiAt(sched.c, 0.49)[0], 0.2326, 1e-15);
  EXPECT_NEAR(truthXiAt(sched.c, 0.5)[0], 0.6326, 1e-12);
  EXPECT_EQ(truthXiAt(sched.c, 0.5)[1], -0.3875);
  const SyntheticDataSettings settings = syntheticSettings(sched.c, *sched.model, 1);
  ASSERT_EQ(settings.schedule.size(), 1u);
  const Eigen::VectorXd p0 = truthParameters(sched.c, *sched.model);
  const Eigen::VectorXd p1 = settings.schedule[0].params;
  const int mass = sched.model->parameterIndex("added_mass");
  EXPECT_NEAR(p1[mass], 263.26, 1e-9);
  EXPECT_NEAR(p0[mass], 223.26, 1e-9);
  EXPECT_EQ((p1 - p0).cwiseAbs().maxCoeff(), std::abs(p1[mass] - p0[mass]));

  // Before the change: the unscheduled truth, bit for bit.
  std::size_t k = 0;
  for (; b[k].time < change; ++k) EXPECT_EQ(b[k].values, a[k].values) << k;
  EXPECT_EQ(k, 3u);
  // After: from the state at 0.5 s, integrated on with the new parameters.
  const MechanicalModel& model = *sched.model;
  auto batch = model.prepare(p0);
  Eigen::ArrayXXd y = batch->initialState();
  double t = 0.0;
  for (std::size_t i = 0; i < k; ++i) {
    integrate(model, *batch, t, b[i].time, y, sched.c.integration);
    t = b[i].time;
  }
  integrate(model, *batch, t, change, y, sched.c.integration);
  t = change;
  batch = model.prepare(p1);
  for (std::size_t i = k; i < b.size(); ++i) {
    integrate(model, *batch, t, b[i].time, y, sched.c.integration);
    t = b[i].time;
    const Eigen::VectorXd z = (model.observationMatrix() * y.matrix()).topRows(4);  // u1 .. v2
    EXPECT_EQ(b[i].values, z) << i;
  }
  // 40 kg more moves the response by millimetres.
  EXPECT_GT(maxDifference(a, b), 1e-3);
}

TEST(SyntheticTruth, LoadChangeCourseConfig) {
  const Case s(loadConfigFile(kDir + "load_change_course.yaml"));
  ASSERT_EQ(s.c.road.source, RoadSource::kCourse);
  ASSERT_EQ(s.c.road.course.size(), 4u);
  const auto* course = dynamic_cast<const CourseRoad*>(s.road.get());
  ASSERT_NE(course, nullptr);
  EXPECT_NEAR(course->boundaries()[2], 10.0, 1e-12);  // second bump
  EXPECT_NEAR(course->boundaries()[4], 13.81, 1e-12);
  EXPECT_DOUBLE_EQ(s.c.sampling.interval(), 0.03);
  ASSERT_EQ(s.c.truth.schedule.size(), 1u);
  EXPECT_EQ(s.c.truth.schedule[0].time, 6.0);
  EXPECT_NEAR(s.c.truth.schedule[0].xi[0], 0.2326 + 0.4, 1e-12);
  EXPECT_EQ(s.c.truth.schedule[0].xi[1], -0.3875);
  // The second bump excites the vehicle again after the rest.
  const MeasurementSeries z = s.clean();
  ASSERT_EQ(z.size(), 450u);
  double rest = 0.0, second = 0.0;
  for (const auto& m : z) {
    const double u = std::abs(m.values[0]);
    if (m.time > 9.0 && m.time < 10.0) rest = std::max(rest, u);
    if (m.time > 10.0 && m.time < 11.0) second = std::max(second, u);
  }
  EXPECT_LT(rest, 1e-3);
  EXPECT_GT(second, 1e-2);
}

// ---------------------------------------------------------------- config errors

void expectError(const std::string& e, const std::string& key, const std::string& what) {
  EXPECT_NE(e.find("test.yaml"), std::string::npos) << e;
  EXPECT_NE(e.find("'" + key), std::string::npos) << e;
  EXPECT_NE(e.find(what), std::string::npos) << e;
}

TEST(SyntheticTruthConfig, BadKeysAreRefusedByName) {
  expectError(errorOf("vehicle: {spring_linaer_left: 2.0e4}"), "truth.vehicle.spring_linaer_left",
              "unknown key");
  expectError(errorOf("vehicle: {added_mass: 250}"), "truth.vehicle.added_mass", "uncertain");
  expectError(errorOf("vehicle: {bar_mass: -1}"), "truth.vehicle.bar_mass", "positive");
  expectError(errorOf("sensor: {bias: [0.1, 0.2, 0.3]}"), "truth.sensor.bias",
              "a list of 4 numbers");
  expectError(errorOf("sensor: {quantisation: -0.1}"), "truth.sensor.quantisation",
              "non-negative");
  expectError(errorOf("sensor: {noise_floor: [0, 0, -1, 0]}"), "truth.sensor.noise_floor[2]",
              "invalid");
  expectError(errorOf("sensor: {gain: 2}"), "truth.sensor.gain", "unknown key");
  expectError(errorOf("timing: {jitter: -0.01}"), "truth.timing.jitter", "non-negative");
  expectError(errorOf("timing: {drop_fraction: 1}"), "truth.timing.drop_fraction", "[0, 1)");
  expectError(errorOf("schedule: [{time: 2, xi: [0, 0]}, {time: 1, xi: [0, 0]}]"),
              "truth.schedule[1].time", "increasing");
  expectError(errorOf("schedule: [{time: 0, xi: [0, 0]}]"), "truth.schedule[0].time", "positive");
  expectError(errorOf("schedule: [{time: 1}]"), "truth.schedule[0].xi", "either xi or values");
  expectError(errorOf("schedule: [{time: 1, values: {bar_mass: 600}}]"),
              "truth.schedule[0].values.bar_mass", "unknown key");
  expectError(errorOf("schedule: [{time: 1, values: {added_mass: 400}}]"),
              "truth.schedule[0].values.added_mass", "support");
  expectError(errorOf("schedule: [{time: 1, xi: [0.1]}]"), "truth.schedule[0].xi",
              "a list of 2 numbers");
  expectError(errorOf("", "road: {source: course}\n"), "road.course", "list of segments");
  expectError(errorOf("", "road: {source: course, course: [{type: gravel}]}\n"),
              "road.course[0].type", "speed_bump, sine, rest, iso8608, turn, lane_change, slalom, brake or accelerate");
  expectError(errorOf("", "road: {source: course, course: [{type: speed_bump}, {type: rest}]}\n"),
              "road.course[1].duration", "positive");
  expectError(errorOf("", "road: {course: [{type: sine, duration: 1, phase: 2}]}\n"),
              "road.course[0].phase", "unknown key");
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
