// IMU channels and the two zero conventions (docs/method.md §1.6): readings at
// rest against closed forms of the static equilibrium, and while driving
// against finite differences of the simulated motion.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "pc_ekf/model/full_car_model.h"
#include "pc_ekf/model/full_car_road.h"
#include "pc_ekf/model/integrator.h"
#include "pc_ekf/model/roll_plane_model.h"

namespace pc_ekf {
namespace {

// Roll-plane reading rows after the 8 dynamic states.
enum Row { kU1 = 8, kU2, kV1, kV2, kAccelY, kAccelZ, kGyroX };

VehicleParameters load(double mass, double position) {
  VehicleParameters p;
  p.added_mass = mass;
  p.added_mass_position = position;
  return p;
}

std::shared_ptr<const ContactRoad> bump() {
  return std::make_shared<SpeedBumpRoad>(SpeedBumpSettings());
}

Eigen::ArrayXXd restReadings(const RollPlaneModel& m, const VehicleParameters& p) {
  Eigen::MatrixXd params = p.toVector();
  return m.prepare(params)->initialState();
}

TEST(RollPlaneReadings, ImuMidwayByDefaultAndFollowsTheMounts) {
  const ModelDescription& d = rollPlaneDescription();
  EXPECT_DOUBLE_EQ(VehicleParameters().imu_position, 0.5 * VehicleParameters().bar_length);
  const ParameterSpec& spec = d.parameters()[d.parameters().at("imu_position")];
  EXPECT_EQ(spec.default_fraction_of, "bar_length");
  EXPECT_DOUBLE_EQ(spec.default_fraction, 0.5);
  EXPECT_EQ(d.defaultChannelNames(), (std::vector<std::string>{"u1", "u2", "v1", "v2"}));
  EXPECT_EQ(d.channelIndex("gyro_x"), 6);
}

TEST(RollPlaneReadings, LinearModelCannotGiveImuChannels) {
  const RollPlaneModel linear(VehicleParameters(), bump());
  EXPECT_EQ(linear.stateSize(), 8);
  EXPECT_TRUE(linear.channelModelled(3));
  EXPECT_FALSE(linear.channelModelled(4));
  const RollPlaneModel tare(VehicleParameters(), bump(), {ZeroConvention::kTare, false});
  EXPECT_EQ(tare.stateSize(), 17);  // tare keeps the readings as states by itself
  EXPECT_EQ(tare.stateNames()[8 + 6], "reading_gyro_x");
  EXPECT_TRUE(tare.channelModelled(6));
}

// Linear springs: delta_i = W_i / k, so the sag and the static roll are closed forms.
TEST(RollPlaneReadings, TareAtRestIsTheSagAndTheStaticTiltClosedForm) {
  VehicleParameters p = load(280.0, 0.90);
  p.spring_cubic[0] = p.spring_cubic[1] = 0.0;
  const RollPlaneModel m(p, bump(), {ZeroConvention::kTare, true});
  const Eigen::ArrayXXd y = restReadings(m, p);
  const double g = p.gravity, L = p.bar_length, k = p.spring_linear[0], kt = p.tyre_stiffness[0];
  const double total = p.bar_mass + p.added_mass;
  const double cg = (p.added_mass * p.added_mass_position + p.bar_mass * 0.5 * L) / total;
  const double w2 = total * g * cg / L, w1 = total * g - w2, w_empty = p.bar_mass * g / 2.0;
  EXPECT_NEAR(y(kU1, 0), -(w1 - w_empty) / k, 1e-12);
  EXPECT_NEAR(y(kU2, 0), -(w2 - w_empty) / k, 1e-12);
  const double h1 = -(w1 / k + (w1 + p.unsprung_mass[0] * g) / kt);
  const double h2 = -(w2 / k + (w2 + p.unsprung_mass[1] * g) / kt);
  const double phi = -std::atan((h2 - h1) / L);  // left up > 0 (REP 103)
  EXPECT_GT(phi, 0.0);                            // the load right of centre: the right sags
  EXPECT_NEAR(y(kAccelY, 0), g * std::sin(phi), 1e-12);
  EXPECT_NEAR(y(kAccelZ, 0), g * std::cos(phi), 1e-12);
  EXPECT_EQ(y(kV1, 0), 0.0);
  EXPECT_EQ(y(kGyroX, 0), 0.0);
  // The paper's vehicle has sags 23-59 mm for these loads: far above 0.5 mm noise.
  EXPECT_LT(y(kU2, 0), -0.04);
}

// The paper's (cubic) springs against the sizes a user can check by hand:
// 150 kg at 0.62 m sags 33 / 23 mm and rolls -8.5 mrad; 280 kg at 0.90 m
// sags 42 / 59 mm and rolls +14.4 mrad.
TEST(RollPlaneReadings, TareSizesForThePapersVehicle) {
  struct Case {
    double mass, position, sag_left, sag_right, roll;
  };
  for (const Case& c : {Case{150.0, 0.62, 0.033, 0.023, -0.0085},
                        Case{280.0, 0.90, 0.042, 0.059, 0.0144}}) {
    const VehicleParameters p = load(c.mass, c.position);
    const RollPlaneModel m(p, bump(), {ZeroConvention::kTare, true});
    const Eigen::ArrayXXd y = restReadings(m, p);
    EXPECT_NEAR(-y(kU1, 0), c.sag_left, 1e-3) << c.mass;
    EXPECT_NEAR(-y(kU2, 0), c.sag_right, 1e-3) << c.mass;
    EXPECT_NEAR(y(kAccelY, 0), p.gravity * std::sin(c.roll), 2e-3) << c.mass;
    // The same sag from the equilibrium solver, loaded minus empty.
    VehicleParameters empty = p;
    empty.added_mass = 0.0;
    const StaticEquilibrium e = solveStaticEquilibrium(p), e0 = solveStaticEquilibrium(empty);
    EXPECT_NEAR(y(kU1, 0), -(e.spring_compression[0] - e0.spring_compression[0]), 1e-15);
  }
}

TEST(RollPlaneReadings, RestReadsZeroAtRest) {
  const VehicleParameters p = load(150.0, 0.62);
  const RollPlaneModel m(p, bump(), {ZeroConvention::kRest, true});
  const Eigen::ArrayXXd y = restReadings(m, p);
  for (int r = kU1; r <= kGyroX; ++r) EXPECT_NEAR(y(r, 0), 0.0, 1e-15) << r;
}

// Over the bump: the accelerometer against central differences of the
// simulated velocities, the gyro against those of the roll, and rest = tare
// minus the readings at rest.
TEST(RollPlaneReadings, DrivingMatchesFiniteDifferencesOfTheMotion) {
  VehicleParameters p = load(280.0, 0.90);
  p.imu_position = 0.4;
  Eigen::MatrixXd params = p.toVector();
  const RollPlaneModel tare(p, bump(), {ZeroConvention::kTare, true});
  const RollPlaneModel rest(p, bump(), {ZeroConvention::kRest, true});
  const auto tb = tare.prepare(params), rb = rest.prepare(params);
  IntegratorSettings s;
  s.max_step = 1e-4;
  const double h = 1e-4, L = p.bar_length, f = p.imu_position / L;
  const Eigen::ArrayXXd tare0 = tb->initialState(), rest0 = rb->initialState();
  for (double t : {0.1, 0.3, 0.45}) {
    Eigen::ArrayXXd y[3];
    for (int j = 0; j < 3; ++j) {
      y[j] = tb->initialState();
      integrate(tare, *tb, 0.0, t + (j - 1) * h, y[j], s);
    }
    const double a = ((1.0 - f) * (y[2](4, 0) - y[0](4, 0)) + f * (y[2](5, 0) - y[0](5, 0))) /
                     (2.0 * h);
    const double phi_s = std::atan2(tare0(kAccelY, 0), tare0(kAccelZ, 0));  // checked above
    const double phi_t = phi_s - (y[1](1, 0) - y[1](0, 0)) / L;
    EXPECT_NEAR(y[1](kAccelZ, 0), (p.gravity + a) * std::cos(phi_t), 2e-4) << t;
    EXPECT_NEAR(y[1](kAccelY, 0), (p.gravity + a) * std::sin(phi_t), 2e-4) << t;
    const double roll_rate = -((y[2](1, 0) - y[2](0, 0)) - (y[0](1, 0) - y[0](0, 0))) / (2 * h * L);
    EXPECT_NEAR(y[1](kGyroX, 0), roll_rate, 1e-5) << t;
    EXPECT_GT(std::abs(y[1](kGyroX, 0)), 1e-3) << t;  // the bump rolls the body
    Eigen::ArrayXXd r = rb->initialState();
    integrate(rest, *rb, 0.0, t, r, s);
    for (int row = kU1; row <= kGyroX; ++row) {
      EXPECT_NEAR(r(row, 0), y[1](row, 0) - tare0(row, 0), 1e-12) << t << " " << row;
    }
  }
}

// Full car: reading rows after the 14 dynamic states.
enum CarRow { kUfl = 14, kVfl = 18, kCarAccelY = 22, kCarAccelZ, kCarGyroX, kCarGyroY };

FullCarParameters loadedCar() {
  FullCarParameters p;
  p.added_mass = 250.0;
  p.added_mass_x = 0.9;
  p.added_mass_y = 1.0;
  p.imu_x = 0.3;
  p.imu_y = -0.2;
  return p;
}

std::shared_ptr<const ContactRoad> carBump(const FullCarParameters& p) {
  FullCarBumpSettings b;
  b.wheelbase = p.wheelbase();
  return std::make_shared<FullCarBumpRoad>(b);
}

TEST(FullCarReadings, TareAtRestAgainstTheEquilibrium) {
  const FullCarParameters p = loadedCar();
  const FullCarModel m(p, carBump(p), {ZeroConvention::kTare, true});
  EXPECT_EQ(m.stateSize(), 29);  // 14 dynamic, 15 readings
  Eigen::MatrixXd params = p.toVector();
  const Eigen::ArrayXXd y = m.prepare(params)->initialState();
  FullCarParameters empty = p;
  empty.added_mass = 0.0;
  const FullCarEquilibrium e = solveFullCarEquilibrium(p), e0 = solveFullCarEquilibrium(empty);
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(y(kUfl + i, 0), -(e.spring_compression[i] - e0.spring_compression[i]), 1e-12);
    EXPECT_LT(y(kUfl + i, 0), 0.0);
    EXPECT_EQ(y(kVfl + i, 0), 0.0);
  }
  // REP 103 pitch is -theta (theta > 0 raises the front).
  const double g = p.gravity;
  EXPECT_NEAR(y(kCarAccelY, 0), g * std::cos(e.pitch) * std::sin(e.roll), 1e-12);
  EXPECT_NEAR(y(kCarAccelZ, 0), g * std::cos(e.pitch) * std::cos(e.roll), 1e-12);
  EXPECT_LT(e.roll, 0.0);  // the load left of centre: the left sags (phi < 0)
  const FullCarModel rest(p, carBump(p), {ZeroConvention::kRest, true});
  const Eigen::ArrayXXd r = rest.prepare(params)->initialState();
  for (int row = kUfl; row <= kCarGyroY; ++row) EXPECT_NEAR(r(row, 0), 0.0, 1e-15) << row;
  EXPECT_NEAR(r(kCarGyroY + 1, 0), 0.0, 1e-15);  // accel_x, less its rest value g theta_s
  EXPECT_NEAR(y(kCarGyroY + 1, 0), g * e.pitch, 1e-15);  // raw: the load's pitch
}

TEST(FullCarReadings, DrivingMatchesFiniteDifferencesOfTheMotion) {
  const FullCarParameters p = loadedCar();
  const FullCarModel m(p, carBump(p), {ZeroConvention::kTare, true});
  Eigen::MatrixXd params = p.toVector();
  const auto b = m.prepare(params);
  const Eigen::ArrayXXd y0 = b->initialState();
  IntegratorSettings s;
  s.max_step = 1e-4;
  const double h = 1e-4;
  for (double t : {0.2, 0.5, 0.9}) {
    Eigen::ArrayXXd y[3];
    for (int j = 0; j < 3; ++j) {
      y[j] = b->initialState();
      integrate(m, *b, 0.0, t + (j - 1) * h, y[j], s);
    }
    const auto rate = [&](int row) { return (y[2](row, 0) - y[0](row, 0)) / (2.0 * h); };
    const double a = rate(7) + p.imu_x * rate(8) + p.imu_y * rate(9);
    const FullCarEquilibrium e = solveFullCarEquilibrium(p);
    const double pitch = -e.pitch - y[1](1, 0), roll = e.roll + y[1](2, 0);
    const double specific = (p.gravity + a) * std::cos(pitch);
    EXPECT_NEAR(y[1](kCarAccelZ, 0), specific * std::cos(roll), 3e-4) << t;
    EXPECT_NEAR(y[1](kCarAccelY, 0), specific * std::sin(roll), 3e-4) << t;
    EXPECT_NEAR(y[1](kCarGyroX, 0), rate(2), 1e-5) << t;
    EXPECT_NEAR(y[1](kCarGyroY, 0), -rate(1), 1e-5) << t;
    // Each corner's extension with the point's own geometry.
    const double u_fl =
        y[1](0, 0) + p.cornerX(0) * y[1](1, 0) + p.cornerY(0) * y[1](2, 0) - y[1](3, 0);
    EXPECT_NEAR(y[1](kUfl, 0) - y0(kUfl, 0), u_fl, 1e-12) << t;
  }
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
