// Heights, anti-roll bar and lateral acceleration in the roll plane
// (docs/models.md): closed forms of the static tilt and of the steady turn,
// the equilibrium's equations, the bar's force signs, the IMU's new terms,
// and the general right-hand side against the paper's with every value 0.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "pc_ekf/model/horizontal_motion.h"
#include "pc_ekf/model/integrator.h"
#include "pc_ekf/model/roll_plane_model.h"
#include "pc_ekf/model/roll_plane_road_free.h"

namespace pc_ekf {
namespace {

enum Row { kX1, kX2, kXr1, kXr2, kX1dot, kX2dot, kAccelY = 12, kAccelZ, kGyroX };

// docs/models.md's reference heights and bar.
VehicleParameters elevated(double mass, double position) {
  VehicleParameters p;
  p.added_mass = mass;
  p.added_mass_position = position;
  p.body_cg_height = 0.25;
  p.added_mass_height = 0.40;
  p.mount_height = 0.40;
  p.wheel_radius = 0.30;
  p.anti_roll_bar = 8000.0;
  return p;
}

VehicleParameters linearSprings(VehicleParameters p) {
  p.spring_cubic[0] = p.spring_cubic[1] = 0.0;
  return p;
}

std::shared_ptr<const ContactRoad> flat() {
  SineSettings s;
  s.amplitude = 0.0;
  return std::make_shared<SineRoad>(s);
}

std::shared_ptr<const ContactRoad> turning(std::shared_ptr<const ContactRoad> road,
                                           double lateral) {
  HorizontalState s;
  s.speed = 20.0;
  s.yaw_rate = lateral / s.speed;
  s.lateral = lateral;
  return std::make_shared<RoadWithMotion>(std::move(road), std::make_shared<SteadyMotion>(s));
}

double firstMoment(const VehicleParameters& p) {
  return p.bar_mass * p.body_cg_height + p.added_mass * p.added_mass_height;
}

// Spring-plus-bar loads from the solved compressions (not the solver's W_i).
void loadsFromCompressions(const VehicleParameters& p, const StaticEquilibrium& e, double w[2]) {
  const double twist = p.anti_roll_bar * (e.spring_compression[0] - e.spring_compression[1]);
  for (int i = 0; i < 2; ++i) {
    const double d = e.spring_compression[i];
    w[i] = p.spring_linear[i] * d + p.spring_cubic[i] * d * d * d + (i == 0 ? twist : -twist);
  }
}

// Linear springs k, tyres k_t (equal sides): (k + 2 k_a)(d1 - d2) = W1 - W2 and
// L t = -(d1 - d2) - (W1 - W2) / k_t, with (W1 - W2) L / 2 = g (M y_M - S t), so
// t = tan(phi_s) = -(2 g c M y_M / L^2) / (1 - 2 g c S / L^2), c = 1/(k + 2 k_a) + 1/k_t.
TEST(RollPlaneHeights, StaticTiltClosedFormWithLinearSprings) {
  for (double bar : {0.0, 8000.0}) {
    VehicleParameters p = linearSprings(elevated(280.0, 0.90));
    p.anti_roll_bar = bar;
    const StaticEquilibrium e = solveStaticEquilibrium(p);
    const double L = p.bar_length, g = p.gravity;
    const double c = 1.0 / (p.spring_linear[0] + 2.0 * bar) + 1.0 / p.tyre_stiffness[0];
    const double y_m = L / 2.0 - p.added_mass_position;
    const double t = -(2.0 * g * c * p.added_mass * y_m / (L * L)) /
                     (1.0 - 2.0 * g * c * firstMoment(p) / (L * L));
    EXPECT_NEAR(std::tan(-e.roll_angle), t, 1e-12) << "k_a = " << bar;
    EXPECT_GT(t, 0.0);  // the load right of centre: the right sags, the left rises
  }
}

// Cubic springs, heights and bar: the three equations of docs/models.md hold
// at the solved state, and the heights tilt further than without them.
TEST(RollPlaneHeights, StaticEquilibriumEquationsHoldAtTheSolvedRest) {
  const VehicleParameters p = elevated(280.0, 0.90);
  const StaticEquilibrium e = solveStaticEquilibrium(p);
  double w[2];
  loadsFromCompressions(p, e, w);
  const double L = p.bar_length, g = p.gravity;
  const double tan_phi = (e.height[0] - e.height[1]) / L;
  EXPECT_NEAR(w[0] + w[1], g * (p.bar_mass + p.added_mass), 1e-9);
  EXPECT_NEAR((w[0] - w[1]) * L / 2.0,
              g * (p.added_mass * (L / 2.0 - p.added_mass_position) - firstMoment(p) * tan_phi),
              1e-9);
  EXPECT_NEAR(std::tan(-e.roll_angle), tan_phi, 1e-15);
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(e.load[i], w[i], 1e-9);
    EXPECT_NEAR(e.height[i],
                -(e.spring_compression[i] + (w[i] + p.unsprung_mass[i] * g) / p.tyre_stiffness[i]),
                1e-15);
  }
  VehicleParameters low = p;
  low.body_cg_height = low.added_mass_height = 0.0;
  const double flat_tilt = std::abs(solveStaticEquilibrium(low).roll_angle);
  EXPECT_GT(std::abs(e.roll_angle), flat_tilt);
  low.anti_roll_bar = 0.0;  // the bar stiffens the roll: without it the tilt grows
  EXPECT_GT(std::abs(solveStaticEquilibrium(low).roll_angle), flat_tilt);
}

// The equilibrium is a rest state of the equations of motion: every
// derivative vanishes there (the S g tan(phi_s) term balances S g sin(phi_s)).
TEST(RollPlaneHeights, RestStaysAtRest) {
  const VehicleParameters p = elevated(280.0, 0.90);
  const RollPlaneModel m(p, flat());
  const auto batch = m.prepare(p.toVector());
  const Eigen::ArrayXXd y = batch->initialState();
  Eigen::ArrayXXd d;
  batch->derivatives(0.3, y, d);
  EXPECT_LT(d.abs().maxCoeff(), 1e-11);
}

// Linear springs, stiff tyres, a steady turn: the body's roll against the
// axle settles at S a_y / (K_phi - S g), K_phi = (k1 + k2) L^2 / 4 + k_a L^2.
TEST(RollPlaneHeights, SteadyTurnRollClosedForm) {
  VehicleParameters p = linearSprings(elevated(200.0, 0.762));
  p.tyre_stiffness[0] = p.tyre_stiffness[1] = 1e8;
  p.damper = DamperLaw::kLinear;
  p.damping[0] = p.damping[1] = 4000.0;  // settles within the run
  const double a_y = 0.5;
  const RollPlaneModel m(p, turning(flat(), a_y));
  const auto batch = m.prepare(p.toVector());
  Eigen::ArrayXXd y = batch->initialState();
  integrate(m, *batch, 0.0, 8.0, y, IntegratorSettings{2e-4, IntegrationMethod::kRk4});
  const double L = p.bar_length, s = firstMoment(p);
  const double k_phi =
      (p.spring_linear[0] + p.spring_linear[1]) * L * L / 4.0 + p.anti_roll_bar * L * L;
  const double expected = s * a_y / (k_phi - s * p.gravity);
  const double roll = ((y(kX1, 0) - y(kXr1, 0)) - (y(kX2, 0) - y(kXr2, 0))) / L;
  EXPECT_GT(roll, 0.0);  // a left turn: the body rolls out of it, left side up
  EXPECT_NEAR(roll, expected, 5e-4 * expected);
  // Without the bar the roll is larger by the ratio of the stiffnesses.
  VehicleParameters soft = p;
  soft.anti_roll_bar = 0.0;
  const RollPlaneModel m_soft(soft, turning(flat(), a_y));
  const auto b_soft = m_soft.prepare(soft.toVector());
  Eigen::ArrayXXd y_soft = b_soft->initialState();
  integrate(m_soft, *b_soft, 0.0, 8.0, y_soft, IntegratorSettings{2e-4, IntegrationMethod::kRk4});
  const double k_soft = (p.spring_linear[0] + p.spring_linear[1]) * L * L / 4.0;
  const double roll_soft =
      ((y_soft(kX1, 0) - y_soft(kXr1, 0)) - (y_soft(kX2, 0) - y_soft(kXr2, 0))) / L;
  EXPECT_NEAR(roll_soft, s * a_y / (k_soft - s * p.gravity), 5e-4 * roll_soft);
}

// The bar's forces: -k_a (u1 - u2) on the left end of the body, +k_a (u1 - u2)
// on the right, the opposite on the unsprung masses.
TEST(RollPlaneHeights, AntiRollBarForceSigns) {
  VehicleParameters p;  // level (load at the middle), no heights
  p.anti_roll_bar = 8000.0;
  VehicleParameters none = p;
  none.anti_roll_bar = 0.0;
  Eigen::ArrayXXd y = Eigen::ArrayXXd::Zero(8, 1);
  const double du = 0.01;
  y(kX1, 0) = du;  // left end up: u1 - u2 = du
  Eigen::ArrayXXd with_bar, without;
  RollPlaneModel(p, flat()).prepare(p.toVector())->derivatives(0.0, y, with_bar);
  RollPlaneModel(none, flat()).prepare(none.toVector())->derivatives(0.0, y, without);
  const double force = p.anti_roll_bar * du;
  EXPECT_NEAR(with_bar(6, 0) - without(6, 0), force / p.unsprung_mass[0], 1e-9);
  EXPECT_NEAR(with_bar(7, 0) - without(7, 0), -force / p.unsprung_mass[1], 1e-9);
  // On the body: no net force; the roll moment -k_a du L cos(phi) pulls the
  // left end down, phi'' = -k_a du L cos(phi) / J, x2'' - x1'' = -L phi''.
  const double L = p.bar_length, phi = du / L;
  const double J = p.bar_inertia;  // D = L/2, M at the middle
  const double rel = L * L * force * std::cos(phi) / J;
  EXPECT_NEAR((with_bar(4, 0) + with_bar(5, 0)) - (without(4, 0) + without(5, 0)), 0.0, 1e-9);
  EXPECT_NEAR((with_bar(5, 0) - with_bar(4, 0)) - (without(5, 0) - without(4, 0)), rel, 1e-9 * rel);
  EXPECT_LT(with_bar(4, 0), without(4, 0));
}

// With every new value 0, the general right-hand side (taken whenever a
// horizontal motion is given, here a_y = 0) is the paper's model: the same
// drive to round-off, readings included.
TEST(RollPlaneHeights, ZeroValuesReproduceThePaperModelOnADrive) {
  VehicleParameters p;
  p.added_mass = 280.0;
  p.added_mass_position = 0.9;
  const auto bump = std::make_shared<SpeedBumpRoad>(SpeedBumpSettings());
  const RollPlaneModel paper(p, bump, {ZeroConvention::kRest, true});
  const RollPlaneModel general(p, turning(bump, 0.0), {ZeroConvention::kRest, true});
  const auto a = paper.prepare(p.toVector());
  const auto b = general.prepare(p.toVector());
  Eigen::ArrayXXd ya = a->initialState(), yb = b->initialState();
  for (int k = 0; k < 10; ++k) {
    integrate(paper, *a, 0.1 * k, 0.1 * (k + 1), ya, IntegratorSettings());
    integrate(general, *b, 0.1 * k, 0.1 * (k + 1), yb, IntegratorSettings());
    for (int r = 0; r < 15; ++r) {
      EXPECT_NEAR(ya(r, 0), yb(r, 0), 1e-12 * (1.0 + std::abs(ya(r, 0)))) << "row " << r;
    }
  }
  EXPECT_GT(ya.col(0).head(8).abs().maxCoeff(), 1e-2);  // the bump moved it
}

// The IMU in a steady turn reads the tilted lateral acceleration:
// accel_y = a_y cos(phi) + g sin(phi) - g sin(phi_s), accel_z = g cos(phi) -
// a_y phi - g cos(phi_s) (rest zero), and its height adds -z_I phi'' to accel_y
// while the body rolls (phi'' from the roll rate's finite difference).
TEST(RollPlaneHeights, ImuReadsTheTurnAndItsHeight) {
  VehicleParameters p = elevated(280.0, 0.90);
  p.damper = DamperLaw::kLinear;
  p.damping[0] = p.damping[1] = 4000.0;
  const double a_y = 4.0;
  const RollPlaneModel m(p, turning(flat(), a_y), {ZeroConvention::kRest, true});
  const auto batch = m.prepare(p.toVector());
  Eigen::ArrayXXd y = batch->initialState();
  integrate(m, *batch, 0.0, 8.0, y, IntegratorSettings());
  const double phi_s = -solveStaticEquilibrium(p).roll_angle, g = p.gravity;
  const double phi = phi_s - (y(kX2, 0) - y(kX1, 0)) / p.bar_length;
  EXPECT_GT(phi - phi_s, 0.02);  // a 4 m/s^2 left turn rolls the body out of it
  EXPECT_NEAR(y(kAccelY, 0), a_y * std::cos(phi) + g * std::sin(phi) - g * std::sin(phi_s), 1e-8);
  EXPECT_NEAR(y(kAccelZ, 0), g * std::cos(phi) - a_y * phi - g * std::cos(phi_s), 1e-8);

  // The turn's onset: the same drive read by an IMU 0.3 m higher.
  VehicleParameters high = p;
  high.imu_height = 0.3;
  const RollPlaneModel m_high(high, turning(flat(), a_y), {ZeroConvention::kRest, true});
  const auto b_low = m.prepare(p.toVector());
  const auto b_high = m_high.prepare(high.toVector());
  const double t = 0.1, h = 1e-4;
  Eigen::ArrayXXd low_t = b_low->initialState(), high_t = b_high->initialState();
  integrate(m, *b_low, 0.0, t, low_t, IntegratorSettings{1e-5, IntegrationMethod::kRk4});
  integrate(m_high, *b_high, 0.0, t, high_t, IntegratorSettings{1e-5, IntegrationMethod::kRk4});
  Eigen::ArrayXXd before = b_low->initialState(), after = b_low->initialState();
  integrate(m, *b_low, 0.0, t - h, before, IntegratorSettings{1e-5, IntegrationMethod::kRk4});
  integrate(m, *b_low, 0.0, t + h, after, IntegratorSettings{1e-5, IntegrationMethod::kRk4});
  const double roll_acc = (after(kGyroX, 0) - before(kGyroX, 0)) / (2.0 * h);
  EXPECT_GT(std::abs(roll_acc), 0.1);
  EXPECT_NEAR(high_t(kAccelY, 0) - low_t(kAccelY, 0), -0.3 * roll_acc, 1e-5);
  EXPECT_NEAR(high_t(kAccelZ, 0) - low_t(kAccelZ, 0), -0.3 * low_t(kGyroX, 0) * low_t(kGyroX, 0),
              1e-10);
}

// Road-free: the model on a road turns on a rough surface with heights, a bar
// and a high IMU; its clean travels, gyro, speed and yaw rate drive the
// road-free model, whose IMU outputs match the model's (the road-free
// equations are the same body's, with the travels as inputs).
TEST(RollPlaneHeights, RoadFreeReproducesTheModelInATurn) {
  for (const ZeroConvention zero : {ZeroConvention::kTare, ZeroConvention::kRest}) {
    VehicleParameters p = elevated(280.0, 0.90);
    p.imu_height = 0.10;
    CourseSegment turn;
    turn.type = CourseSegment::Type::kSlalom;
    turn.duration = 3.0;
    turn.speed_kmh = 50.0;
    turn.manoeuvre.lateral_acceleration = 3.5;
    turn.manoeuvre.frequency = 0.5;
    turn.manoeuvre.rough = true;
    turn.iso8608.road_class = 'B';
    const RollPlaneModel full(p, std::make_shared<CourseRoad>(std::vector<CourseSegment>{turn}),
                              {zero, true});
    const auto batch = full.prepare(p.toVector());
    Eigen::ArrayXXd y = batch->initialState();
    const IntegratorSettings is{2.5e-4, IntegrationMethod::kRk4};
    std::vector<double> times;
    std::vector<std::vector<double>> in(7);
    std::vector<double> accel_y, accel_z, gyro;
    double t = 0.0;
    for (int k = 1; k <= 500; ++k) {
      const double tk = k * 0.005;
      integrate(full, *batch, t, tk, y, is);
      t = tk;
      times.push_back(tk);
      for (int c = 0; c < 4; ++c) in[c].push_back(y(8 + c, 0));
      in[4].push_back(y(kGyroX, 0));
      in[5].push_back(y(15, 0));  // speed
      in[6].push_back(y(16, 0));  // gyro_z
      accel_y.push_back(y(kAccelY, 0));
      accel_z.push_back(y(kAccelZ, 0));
      gyro.push_back(y(kGyroX, 0));
    }
    auto inputs = std::make_shared<ReadingInputs>(
        std::vector<std::string>{"u1", "u2", "v1", "v2", "gyro_x", "speed", "gyro_z"}, times, in);
    const RollPlaneRoadFreeModel free(p, inputs, zero);
    EXPECT_TRUE(free.channelIsInput(7));
    EXPECT_TRUE(free.channelIsInput(8));
    const auto fb = free.prepare(p.toVector());
    double worst_y = 0.0, worst_z = 0.0, worst_gyro = 0.0, swing = 0.0;
    for (std::size_t k = 0; k < times.size(); ++k) {
      Eigen::ArrayXXd r = fb->initialState();
      fb->readings(times[k], r);
      worst_y = std::max(worst_y, std::abs(r(0, 0) - accel_y[k]));
      worst_z = std::max(worst_z, std::abs(r(1, 0) - accel_z[k]));
      worst_gyro = std::max(worst_gyro, std::abs(r(2, 0) - gyro[k]));
      swing = std::max(swing, std::abs(accel_y[k]));
    }
    EXPECT_GT(swing, 3.0);        // the slalom's a_y
    EXPECT_LT(worst_y, 5e-3);     // the gyro's integral by trapezoids
    EXPECT_LT(worst_z, 5e-3);     // cos(phi) of the dynamic roll
    EXPECT_LT(worst_gyro, 2e-3);  // the increment's trapezoid over 5 ms
    // Without speed and yaw rate the road-free model misses a_y: accel_y off by metres/s^2.
    std::vector<std::vector<double>> no_turn(in.begin(), in.begin() + 5);
    const RollPlaneRoadFreeModel blind(
        p,
        std::make_shared<ReadingInputs>(std::vector<std::string>{"u1", "u2", "v1", "v2", "gyro_x"},
                                        times, no_turn),
        zero);
    const auto bb = blind.prepare(p.toVector());
    Eigen::ArrayXXd r = bb->initialState();
    bb->readings(times[150], r);  // a quarter period into the slalom: a_y at its peak
    EXPECT_GT(std::abs(r(0, 0) - accel_y[150]), 2.0);
  }
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
