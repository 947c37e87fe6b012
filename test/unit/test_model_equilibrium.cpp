// Static equilibrium (docs/method.md §1.3), parameter vector and admissibility checks.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>

#include "pc_ekf/model/roll_plane_model.h"

namespace pc_ekf {
namespace {

constexpr double kDeg = 180.0 / 3.14159265358979323846;

// docs/method.md §1.1: M = 200 (1 + 0.5 xi1), d_CG = 0.762 (1 + 0.25 xi2).
VehicleParameters at(double xi1, double xi2) {
  VehicleParameters p;
  p.added_mass = 200.0 * (1.0 + 0.5 * xi1);
  p.added_mass_position = 0.762 * (1.0 + 0.25 * xi2);
  return p;
}

RollPlaneModel makeModel() {
  return RollPlaneModel(VehicleParameters(), std::make_shared<SineRoad>(SineSettings()));
}

TEST(StaticEquilibrium, ReferenceValuesAtXiOneOne) {
  const VehicleParameters p = at(1.0, 1.0);
  EXPECT_DOUBLE_EQ(p.added_mass, 300.0);
  EXPECT_DOUBLE_EQ(p.added_mass_position, 0.9525);
  const StaticEquilibrium e = solveStaticEquilibrium(p);
  EXPECT_NEAR(e.roll_angle * kDeg, -1.2093, 5e-4);
  EXPECT_NEAR(e.height[1] - e.height[0], -0.03217, 1e-5);
  // D = (300 * 0.9525 + 580 * 0.762) / 880; loads share the weight by lever arms.
  EXPECT_NEAR(e.combined_cg, 0.8269431818, 1e-9);
  EXPECT_NEAR(e.load[0] + e.load[1], 880.0 * 9.81, 1e-9);
  EXPECT_NEAR(e.load[1], 4684.275, 1e-6);
  for (int i = 0; i < 2; ++i) {
    const double d = e.spring_compression[i];
    EXPECT_NEAR(19357.2 * d + 1e5 * d * d * d, e.load[i], 1e-9 * e.load[i]);
  }
  EXPECT_NEAR(e.height[0], -0.22056406, 1e-7);
}

TEST(StaticEquilibrium, MirrorPointHasOppositeSigns) {
  const StaticEquilibrium a = solveStaticEquilibrium(at(1.0, 1.0));
  const StaticEquilibrium b = solveStaticEquilibrium(at(1.0, -1.0));
  EXPECT_DOUBLE_EQ(at(1.0, -1.0).added_mass_position, 0.5715);
  EXPECT_NEAR(b.roll_angle * kDeg, 1.2093, 5e-4);
  EXPECT_NEAR(b.height[1] - b.height[0], 0.03217, 1e-5);
  EXPECT_NEAR(b.roll_angle, -a.roll_angle, 1e-12);
}

TEST(StaticEquilibrium, LevelAtNominal) {
  const StaticEquilibrium e = solveStaticEquilibrium(at(0.0, 0.0));
  EXPECT_NEAR(e.roll_angle, 0.0, 1e-14);
  EXPECT_NEAR(e.height[1] - e.height[0], 0.0, 1e-15);
  EXPECT_NEAR(e.load[0], 780.0 * 9.81 / 2.0, 1e-9);
}

TEST(StaticEquilibrium, LinearSpringIsLoadOverStiffness) {
  VehicleParameters p = at(0.5, -0.3);
  p.spring_cubic[0] = p.spring_cubic[1] = 0.0;
  const StaticEquilibrium e = solveStaticEquilibrium(p);
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(e.spring_compression[i], e.load[i] / 19357.2, 1e-15);
  }
}

TEST(StaticEquilibrium, NonFiniteInputThrows) {
  VehicleParameters p;
  p.gravity = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(solveStaticEquilibrium(p), std::runtime_error);
}

TEST(VehicleParametersVector, OrderAndRoundTrip) {
  const RollPlaneModel model = makeModel();
  ASSERT_EQ(rollPlaneDescription().parameters().names().size(), 24u);
  EXPECT_EQ(model.parameterIndex("bar_mass"), 0);
  EXPECT_EQ(model.parameterIndex("spring_cubic_right"), 8);
  EXPECT_EQ(model.parameterIndex("gravity"), 13);
  EXPECT_EQ(model.parameterIndex("added_mass"), 14);
  EXPECT_EQ(model.parameterIndex("added_mass_position"), 15);
  EXPECT_EQ(model.parameterIndex("imu_position"), 16);
  EXPECT_EQ(model.parameterIndex("body_cg_height"), 17);  // the heights and bar after them
  EXPECT_EQ(model.parameterIndex("anti_roll_bar"), 22);
  EXPECT_EQ(model.parameterIndex("body_cg_offset"), 23);  // last: the vector before it unchanged
  EXPECT_EQ(model.parameterIndex("no_such_parameter"), -1);

  VehicleParameters p = at(0.3, 0.7);
  p.damping[1] = 650.0;
  p.tyre_stiffness[0] = 90000.0;
  const Eigen::VectorXd v = p.toVector();
  EXPECT_DOUBLE_EQ(v[4], 650.0);
  EXPECT_DOUBLE_EQ(v[11], 90000.0);
  EXPECT_DOUBLE_EQ(v[14], 230.0);
  VehicleParameters laws;
  laws.damper = DamperLaw::kLinear;
  laws.damper_tanh_rate = 7.0;
  const VehicleParameters back = VehicleParameters::fromVector(v, laws);
  EXPECT_EQ(back.toVector(), v);
  EXPECT_EQ(back.damper, DamperLaw::kLinear);
  EXPECT_EQ(back.damper_tanh_rate, 7.0);
  EXPECT_THROW(VehicleParameters::fromVector(Eigen::VectorXd::Zero(15), laws),
               std::invalid_argument);
}

TEST(InvalidReason, NamesTheOffendingParameter) {
  const RollPlaneModel model = makeModel();
  Eigen::VectorXd v = model.nominalParameters();
  EXPECT_EQ(model.invalidReason(v), "");

  v[15] = 1.6;  // beyond L = 1.524
  std::string why = model.invalidReason(v);
  EXPECT_NE(why.find("added_mass_position"), std::string::npos) << why;
  EXPECT_NE(why.find("1.6"), std::string::npos) << why;
  v[15] = -0.01;
  EXPECT_NE(model.invalidReason(v).find("added_mass_position"), std::string::npos);
  v[15] = 1.524;  // the end itself is admissible
  EXPECT_EQ(model.invalidReason(v), "");

  v = model.nominalParameters();
  v[14] = -580.0;  // M <= -m
  why = model.invalidReason(v);
  EXPECT_NE(why.find("added_mass"), std::string::npos) << why;
  EXPECT_NE(why.find("-580"), std::string::npos) << why;
  v[14] = -579.0;  // negative but total mass 1 kg: still a mechanical system
  EXPECT_EQ(model.invalidReason(v), "");

  v = model.nominalParameters();
  v[10] = std::numeric_limits<double>::infinity();
  EXPECT_NE(model.invalidReason(v).find("bar_inertia"), std::string::npos);
  v = model.nominalParameters();
  v[3] = -1.0;
  EXPECT_NE(model.invalidReason(v).find("damping_left"), std::string::npos);
  v = model.nominalParameters();
  v[7] = 0.0;  // linear spring is admissible
  EXPECT_EQ(model.invalidReason(v), "");
  EXPECT_NE(model.invalidReason(Eigen::VectorXd::Ones(3)), "");
}

TEST(InvalidReason, PrepareRejectsInadmissibleColumn) {
  const RollPlaneModel model = makeModel();
  Eigen::MatrixXd params(model.nominalParameters().size(), 2);
  params.col(0) = model.nominalParameters();
  params.col(1) = model.nominalParameters();
  params(15, 1) = 2.0;
  EXPECT_THROW(model.prepare(params), std::invalid_argument);
  params(15, 1) = 0.5;
  EXPECT_EQ(model.prepare(params)->pointCount(), 2);
}

TEST(RollPlaneModel, ObservationMatrixGivesExtensionsAndRates) {
  const RollPlaneModel model = makeModel();
  Eigen::VectorXd s(8);
  s << 1.0, 2.0, 0.25, 0.5, -1.0, 3.0, 0.5, 1.0;
  const Eigen::Vector4d z = model.observationMatrix() * s;
  EXPECT_EQ(z, Eigen::Vector4d(0.75, 1.5, -1.5, 2.0));
  EXPECT_EQ(model.channelNames()[3], "v2");
  EXPECT_EQ(model.stateNames()[6], "xr1dot");
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
