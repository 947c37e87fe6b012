// The full car through the whole offline path: config (model.type full_car),
// synthetic data, every estimator, the exact posterior in three dimensions,
// CSV with the model's channel names.
#include <gtest/gtest.h>

#include <sstream>

#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/io/measurement_csv.h"
#include "pc_ekf/io/offline_estimation.h"

namespace pc_ekf {
namespace {

const std::string kConfig = std::string(PC_EKF_SOURCE_DIR) + "/config/full_car_bump.yaml";

struct FullCarRun {
  EstimatorConfig c = loadConfigFile(kConfig);
  std::shared_ptr<const MechanicalModel> model = makeModel(c, makeRoad(c));
  MeasurementSeries data = synthesizeFromConfig(c, *model, 1);
  OfflineResult estimate(EstimationMethod m) const { return runOfflineEstimation(c, data, model, m, 1); }
};

TEST(FullCarConfig, ModelTypeGivesChannelsContactsAndParameters) {
  const FullCarRun r;
  EXPECT_EQ(r.c.model_type->name(), "full_car");
  EXPECT_EQ(r.model->stateSize(), 14);
  EXPECT_EQ(r.c.measurement.channels,
            (std::vector<std::string>{"u_fl", "u_fr", "u_rl", "u_rr", "v_fl", "v_fr", "v_rl", "v_rr"}));
  EXPECT_EQ(r.c.model_type->contactNames(),
            (std::vector<std::string>{"front_left", "front_right", "rear_left", "rear_right"}));
  ASSERT_EQ(r.c.uncertain.size(), 3u);
  EXPECT_EQ(r.c.uncertain[2].name, "added_mass_y");
  ASSERT_EQ(r.data.size(), 100u);
  EXPECT_EQ(r.data[0].channels.size(), 8u);
  // The road: left front wheel first, right wheels 0.6 m later, rear a + b later.
  Eigen::VectorXd y(4);
  makeRoad(r.c)->heights(0.5 / (16.0 / 3.6), y);  // 0.5 m of travel
  EXPECT_NEAR(y[0], 0.05, 1e-12);
  EXPECT_EQ(y[1], 0.0);
  EXPECT_EQ(y[2], 0.0);
}

TEST(FullCarConfig, BadModelKeysAreNamed) {
  const std::pair<const char*, const char*> bad[] = {
      {"model: {type: half_car}\n", "model.type"},
      {"model: {type: full_car}\nvehicle: {bar_mass: 500}\n", "vehicle.bar_mass"},
      {"model: {type: full_car}\nroad: {source: sine}\n", "road.source"},
      {"model: {type: full_car}\nuncertain: [{name: added_mass_position, nominal: 1, "
       "relative_range: 0.1}]\n", "uncertain[0].name"},
      {"model: {type: full_car}\nmeasurement: {channels: [u1]}\n", "measurement.channels"},
  };
  for (const auto& [text, key] : bad) {
    std::string yaml = text;
    if (yaml.find("uncertain") == std::string::npos) {
      yaml += "uncertain: [{name: added_mass, nominal: 200, relative_range: 0.5}]\n";
    }
    try {
      const EstimatorConfig c = parseConfigString(yaml, "bad.yaml");
      makeRoad(c);  // road-source checks need the model
      ADD_FAILURE() << "accepted: " << yaml;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  }
}

TEST(FullCarEstimation, OneStepAndEsMdaCoverTheTruthAndEsMdaMatchesTheExactPosterior) {
  const FullCarRun r;
  const std::vector<double> truth{0.2326, -0.3875, 0.3};
  const OfflineResult grid = r.estimate(EstimationMethod::kGrid);
  ASSERT_EQ(grid.modes, 1);
  EXPECT_LT(grid.border_mass, 1e-6);
  for (auto m : {EstimationMethod::kOneStep, EstimationMethod::kEsMda}) {
    const OfflineResult e = r.estimate(m);
    EXPECT_TRUE(e.healthy) << toString(m);
    for (std::size_t i = 0; i < truth.size(); ++i) {
      const ParameterSummary& p = e.parameters[i];
      EXPECT_LT(std::abs(p.xi_mean - truth[i]), 3.0 * p.xi_stddev) << toString(m) << " " << p.name;
      if (m == EstimationMethod::kEsMda) {
        const ParameterSummary& g = grid.parameters[i];
        EXPECT_LT(std::abs(p.mean - g.mean), 1.0 * g.stddev) << p.name;
        EXPECT_GT(p.stddev, 0.5 * g.stddev) << p.name;
        EXPECT_LT(p.stddev, 2.0 * g.stddev) << p.name;
      }
    }
  }
}

TEST(FullCarEstimation, StifferRearSpringsAreFlagged) {
  FullCarRun r;
  EstimatorConfig truth = r.c;
  auto car = std::const_pointer_cast<ModelParameters>(truth.model_type->defaults());
  car->values = r.c.modelParameters()->values;
  const auto& names = truth.model_type->parameterNames();
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i] == "spring_linear_rear") car->values[i] *= 1.05;
  }
  truth.model = car;
  const auto truth_model = makeModel(truth, makeRoad(truth));
  r.data = synthesizeFromConfig(truth, *truth_model, 1);
  for (auto m : {EstimationMethod::kOneStep, EstimationMethod::kEsMda}) {
    EXPECT_FALSE(r.estimate(m).healthy) << toString(m);
  }
}

TEST(FullCarCsv, ChannelNamesAreTheHeaderAndRoundTrip) {
  const FullCarRun r;
  const auto& names = r.c.model_type->channelNames();
  std::stringstream text;
  writeMeasurementCsv(text, r.data, names);
  std::string header;
  std::getline(text, header);
  EXPECT_EQ(header, "t,u_fl,u_fr,u_rl,u_rr,v_fl,v_fr,v_rl,v_rr");
  text.seekg(0);
  const MeasurementSeries back = readMeasurementCsv(text, "full_car.csv", names);
  ASSERT_EQ(back.size(), r.data.size());
  for (std::size_t k = 0; k < back.size(); ++k) {
    EXPECT_EQ(back[k].channels, r.data[k].channels);
    EXPECT_EQ(back[k].values, r.data[k].values);  // 17 digits: exact
  }
  // A roll-plane header is refused, naming the expected one.
  std::stringstream roll("t,u1,u2,v1,v2\n0.1,0,0,0,0\n");
  try {
    readMeasurementCsv(roll, "roll.csv", names);
    ADD_FAILURE();
  } catch (const CsvError& e) {
    EXPECT_NE(std::string(e.what()).find("u_fl"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
