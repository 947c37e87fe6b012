// Vehicle values as a datasheet gives them (docs/models.md "Datasheet
// values"): spring and damper rates at the spring with a motion ratio, a
// measured damper table (bump and rebound), the tracks, and the roll plane's
// lateral offset of the empty body's centre of mass. The io layer converts
// them to the model's wheel values; these tests hold the conversions to the
// equivalent wheel-rate model and to hand computations.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>

#include "pc_ekf/io/config_error.h"
#include "pc_ekf/io/estimator_config.h"
#include "pc_ekf/model/integrator.h"
#include "pc_ekf/model/roll_plane_model.h"

namespace pc_ekf {
namespace {

const char* kUncertain =
    "uncertain:\n"
    "  - {name: added_mass, nominal: 200.0, relative_range: 0.5}\n"
    "  - {name: added_mass_position, nominal: 0.762, relative_range: 0.25}\n";

EstimatorConfig parse(const std::string& vehicle) {
  return parseConfigString("vehicle: {" + vehicle + "}\n" + kUncertain, "datasheet.yaml");
}

std::string errorOf(const std::string& vehicle) {
  try {
    parse(vehicle);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

// The 8 states at 0.01 s steps over 3 s of the out-of-phase sine, every state
// row kept (readings u, v follow from them).
Eigen::MatrixXd trajectory(const ModelParameters& p) {
  const RollPlaneModel model(p, std::make_shared<SineRoad>(SineSettings{}));
  const auto batch = model.prepare(p.values);
  Eigen::ArrayXXd y = batch->initialState();
  Eigen::MatrixXd out(8, 300);
  for (int k = 0; k < 300; ++k) {
    integrate(model, *batch, 0.01 * k, 0.01 * (k + 1), y, IntegratorSettings());
    out.col(k) = y.col(0).matrix();
  }
  return out;
}

double relativeDifference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  double worst = 0.0;
  for (Eigen::Index r = 0; r < a.rows(); ++r) {
    const double scale = a.row(r).cwiseAbs().maxCoeff();
    worst = std::max(worst, (a.row(r) - b.row(r)).cwiseAbs().maxCoeff() / scale);
  }
  return worst;
}

// Spring 32000 N/m and damper 2000 N s/m at the spring, motion ratio 0.6:
// the wheel rates 32000 x 0.36 and 2000 x 0.36.
TEST(DatasheetValues, LinearTableWithMotionRatioIsTheWheelRateLinearModel) {
  const EstimatorConfig wheel = parse(
      "damper: linear, spring_cubic_left: 0, spring_cubic_right: 0, "
      "spring_linear_left: 11520, spring_linear_right: 11520, "
      "damping_left: 720, damping_right: 720");
  const EstimatorConfig sheet = parse(
      "spring_cubic_left: 0, spring_cubic_right: 0, "
      "spring_rate_left: 32000, spring_rate_right: 32000, "
      "motion_ratio_left: 0.6, motion_ratio_right: 0.6, "
      "damper_table: {bump: [[0.5, 1000]], rebound: [[0.5, 1000]]}");
  EXPECT_EQ(sheet.model->choices[0], "table");
  const Eigen::VectorXd& a = wheel.model->values;
  const Eigen::VectorXd& b = sheet.model->values;
  ASSERT_EQ(a.size(), b.size());
  for (Eigen::Index i = 0; i < a.size(); ++i) {
    EXPECT_NEAR(b[i], a[i], 1e-12 * std::abs(a[i])) << rollPlaneDescription().parameters().names()[i];
  }
  const double error = relativeDifference(trajectory(*wheel.model), trajectory(*sheet.model));
  std::printf("linear table + motion ratio vs wheel-rate linear model: %.2e\n", error);
  EXPECT_LT(error, 1e-12);
}

// Bump 300 N at 0.1 m/s, 800 N at 0.5; rebound 600 N at 0.1, 1500 N at 0.5
// (at the damper), motion ratio 0.8: at the wheel, w = v / 0.8, F = 0.8 F_d,
// linear between the points and beyond them along the end segments.
TEST(DatasheetValues, AsymmetricTableGivesTheClosedFormForce) {
  const EstimatorConfig c = parse(
      "motion_ratio_left: 0.8, motion_ratio_right: 0.8, "
      "damper_table: {bump: [[0.1, 300], [0.5, 800]], rebound: [[0.1, 600], [0.5, 1500]]}");
  const auto force = [](double w) {  // closed form at the wheel
    const double v = 0.8 * w, a = std::abs(v);
    const double f1 = v > 0 ? 600.0 : 300.0, f2 = v > 0 ? 1500.0 : 800.0;
    const double fd = a <= 0.1 ? f1 * a / 0.1 : f1 + (a - 0.1) * (f2 - f1) / 0.4;
    return std::copysign(0.8 * fd, v);
  };
  const VehicleParameters p = VehicleParameters::from(*c.model);
  // The table as measured: damping = its mean slope at 0, at the wheel.
  const double reference = 0.5 * (3000.0 + 6000.0) * 0.64;
  EXPECT_NEAR(p.damping[0], reference, 1e-9);
  const RollPlaneModel model(*c.model, std::make_shared<SineRoad>(SineSettings{0.0, 1.0, -1.0}));
  const auto batch = model.prepare(c.model->values);
  for (const double w : {-1.0, -0.4, -0.1, -0.01, 0.0, 0.02, 0.1, 0.3, 0.625, 0.9}) {
    // Extension rate w on the left, everything else at the equilibrium: the
    // unsprung mass feels the damper alone.
    Eigen::ArrayXXd y = Eigen::ArrayXXd::Zero(8, 1), d;
    y(4, 0) = w;
    batch->derivatives(0.0, y, d);
    const double got = d(6, 0) * p.unsprung_mass[0];
    EXPECT_NEAR(got, force(w), 1e-9 * std::max(1.0, std::abs(force(w)))) << "w = " << w;
    EXPECT_NEAR(p.damper_curve[0](w), force(w), 1e-9 * std::max(1.0, std::abs(force(w))));
  }
}

// e_b = 0 is today's model: the combined centre (M d + m L / 2) / (M + m).
TEST(DatasheetValues, BodyOffsetZeroIsTodaysModel) {
  const EstimatorConfig given = parse("body_cg_offset: 0.0");
  const EstimatorConfig absent = parse("bar_mass: 580.0");
  EXPECT_EQ(given.model->values, absent.model->values);
  const VehicleParameters p = VehicleParameters::from(*given.model);
  const StaticEquilibrium e = solveStaticEquilibrium(p);
  EXPECT_EQ(e.combined_cg, (p.added_mass * p.added_mass_position + p.bar_mass * 0.5 * p.bar_length) /
                               (p.added_mass + p.bar_mass));
  EXPECT_EQ(trajectory(*given.model), trajectory(*absent.model));
}

// Linear springs: D = (M d + m (L/2 - e_b)) / (M + m), W_2 = (m + M) g D / L,
// delta_i = W_i / k_i, h_i = -(delta_i + (W_i + m_t g) / k_t).
TEST(DatasheetValues, BodyOffsetMovesTheStaticEquilibrium) {
  const EstimatorConfig c = parse(
      "body_cg_offset: 0.05, spring_cubic_left: 0, spring_cubic_right: 0, added_mass: 150");
  const VehicleParameters p = VehicleParameters::from(*c.model);
  const double m = p.bar_mass, M = p.added_mass, L = p.bar_length, g = p.gravity;
  const double D = (M * p.added_mass_position + m * (L / 2 - 0.05)) / (M + m);
  const double w2 = (m + M) * g * D / L, w1 = (m + M) * g - w2;
  const double h1 = -(w1 / p.spring_linear[0] + (w1 + p.unsprung_mass[0] * g) / p.tyre_stiffness[0]);
  const double h2 = -(w2 / p.spring_linear[1] + (w2 + p.unsprung_mass[1] * g) / p.tyre_stiffness[1]);
  const StaticEquilibrium e = solveStaticEquilibrium(p);
  EXPECT_NEAR(e.combined_cg, D, 1e-14);
  EXPECT_NEAR(e.load[0], w1, 1e-9);
  EXPECT_NEAR(e.height[0], h1, 1e-13);
  EXPECT_NEAR(e.height[1], h2, 1e-13);
  EXPECT_NEAR(e.roll_angle, std::atan((h2 - h1) / L), 1e-13);
  // The body left of the middle: the left side sinks (theta_s > 0 here: the
  // load at its nominal place alone leaves the bar level).
  EXPECT_GT(e.roll_angle, solveStaticEquilibrium(VehicleParameters::from(
                              *parse("spring_cubic_left: 0, spring_cubic_right: 0, "
                                     "added_mass: 150")
                                   .model))
                              .roll_angle);
}

TEST(DatasheetValues, TracksAndAxleLoads) {
  EXPECT_DOUBLE_EQ(VehicleParameters::from(*parse("wheel_track: 1.6").model).bar_length, 1.6);
  EXPECT_DOUBLE_EQ(VehicleParameters::from(*parse("spring_track: 1.2, motion_ratio_left: 0.75, "
                                                  "motion_ratio_right: 0.75")
                                                .model)
                       .bar_length,
                   1.6);
  const EstimatorConfig car = parseConfigString(
      "model: {type: full_car}\nvehicle: {wheelbase: 2.5, front_axle_load_share: 0.6}\n"
      "uncertain:\n  - {name: added_mass, nominal: 200.0, relative_range: 0.5}\n",
      "car.yaml");
  const ParameterTable& t = car.model_type->description().parameters();
  EXPECT_DOUBLE_EQ(car.model->values[t.at("front_axle_distance")], 1.0);
  EXPECT_DOUBLE_EQ(car.model->values[t.at("rear_axle_distance")], 1.5);
}

// config/examples/compact_car_front.yaml: the datasheet forms as shipped.
TEST(DatasheetValues, ExampleVehicleReadsToWheelValues) {
  const EstimatorConfig c = loadConfigFile(std::string(PC_EKF_SOURCE_DIR) +
                                           "/config/examples/compact_car_front.yaml");
  const VehicleParameters p = VehicleParameters::from(*c.model);
  EXPECT_EQ(p.damper, DamperLaw::kTable);
  EXPECT_NEAR(p.spring_linear[0], 28000.0 * 0.92 * 0.92, 1e-9);
  EXPECT_NEAR(p.spring_cubic[1], 150000.0 * std::pow(0.92, 4), 1e-8);
  EXPECT_NEAR(p.damping[0], 0.5 * (2400.0 + 4600.0) * 0.95 * 0.95, 1e-9);
  EXPECT_DOUBLE_EQ(p.bar_length, 1.47);
  EXPECT_DOUBLE_EQ(p.body_cg_offset, 0.012);
}

// calibrate_vehicle writes wheel values: a vehicle file's spring_linear_left
// replaces the config's spring_rate_left (and the motion ratio it no longer
// needs), its damping_left scales the config's table.
TEST(DatasheetValues, VehicleFileReplacesTheDatasheetForm) {
  const std::string file = ::testing::TempDir() + "/datasheet_vehicle.yaml";
  std::ofstream(file) << "vehicle: {spring_linear_left: 12345.0, damping_left: 2000.0}\n";
  const EstimatorConfig c = parseConfigString(
      "vehicle_file: " + file +
          "\nvehicle: {spring_rate_left: 30000, motion_ratio_left: 0.6, "
          "motion_ratio_right: 0.8, damper_table: {bump: [[0.5, 400]], rebound: [[0.5, 900]]}}\n" +
          kUncertain,
      "with_file.yaml");
  const VehicleParameters p = VehicleParameters::from(*c.model);
  EXPECT_DOUBLE_EQ(p.spring_linear[0], 12345.0);
  EXPECT_DOUBLE_EQ(p.damping[0], 2000.0);
  EXPECT_EQ(p.damper, DamperLaw::kTable);
  EXPECT_NEAR(p.damping[1], 0.5 * (800.0 + 1800.0) * 0.64, 1e-9);  // the table's, right
}

TEST(DatasheetValues, BadInputNamesTheKey) {
  const std::string falling = errorOf(
      "motion_ratio_left: 1, motion_ratio_right: 1, "
      "damper_table: {bump: [[0.1, 300], [0.5, 200]], rebound: [[0.1, 600]]}");
  EXPECT_NE(falling.find("damper_table"), std::string::npos) << falling;
  EXPECT_NE(falling.find("monotone"), std::string::npos) << falling;
  const std::string zero_ratio = errorOf("motion_ratio_left: 0, spring_rate_left: 30000");
  EXPECT_NE(zero_ratio.find("motion_ratio_left"), std::string::npos) << zero_ratio;
  const std::string negative = errorOf("motion_ratio_right: -0.5, spring_rate_right: 30000");
  EXPECT_NE(negative.find("motion_ratio_right"), std::string::npos) << negative;
  const std::string tracks = errorOf("wheel_track: 1.6, spring_track: 1.2");
  EXPECT_NE(tracks.find("wheel_track"), std::string::npos) << tracks;
  EXPECT_NE(tracks.find("spring_track"), std::string::npos) << tracks;
  const std::string twice = errorOf("spring_rate_left: 30000, motion_ratio_left: 0.6, "
                                    "spring_linear_left: 10000");
  EXPECT_NE(twice.find("spring_rate_left"), std::string::npos) << twice;
  const std::string off_zero = errorOf(
      "motion_ratio_left: 1, motion_ratio_right: 1, "
      "damper_table: {bump: [[0, 50], [0.5, 800]], rebound: [[0.5, 600]]}");
  EXPECT_NE(off_zero.find("(0, 0)"), std::string::npos) << off_zero;
  const std::string no_table = errorOf("damper: table");
  EXPECT_NE(no_table.find("damper"), std::string::npos) << no_table;
  const std::string far = errorOf("body_cg_offset: 0.9");
  EXPECT_NE(far.find("body_cg_offset"), std::string::npos) << far;
  for (const std::string& e : {falling, zero_ratio, tracks, twice, off_zero, no_table, far}) {
    std::printf("%s\n", e.c_str());
  }
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
