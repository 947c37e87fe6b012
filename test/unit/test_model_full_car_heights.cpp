// Heights, anti-roll bars and horizontal accelerations in the full car
// (docs/models.md): the equilibrium's three body equations, rest, the steady
// turn's roll and the steady brake's pitch against closed forms, the bars'
// force signs, the IMU channels against finite differences of the simulated
// motion, every new value 0 against today's right-hand side, the road-free
// outputs against the model's, and the course's brake and rear wheels.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "pc_ekf/model/course_motion.h"
#include "pc_ekf/model/full_car_model.h"
#include "pc_ekf/model/full_car_road.h"
#include "pc_ekf/model/full_car_road_free.h"
#include "pc_ekf/model/horizontal_motion.h"
#include "pc_ekf/model/integrator.h"

namespace pc_ekf {
namespace {

// Dynamic rows and reading rows (readings as states: 14 + channel).
enum Row {
  kZ, kTheta, kPhi, kZuFl, kZuFr, kZuRl, kZuRr, kZdot, kThetadot, kPhidot,
  kU = 14, kV = 18, kAccelY = 22, kAccelZ, kGyroX, kGyroY, kAccelX, kSpeed, kGyroZ
};

// docs/models.md's reference heights and bars, M off the centre line.
FullCarParameters elevated() {
  FullCarParameters p;
  p.added_mass = 250.0;
  p.added_mass_x = 1.0;
  p.added_mass_y = 0.45;
  p.body_cg_height = 0.20;
  p.added_mass_height = 0.40;
  p.mount_height = 0.40;
  p.wheel_radius = 0.30;
  p.imu_height = 0.10;
  p.anti_roll_bar[0] = 10000.0;
  p.anti_roll_bar[1] = 6000.0;
  return p;
}

double firstMoment(const FullCarParameters& p) {
  return p.body_mass * p.body_cg_height + p.added_mass * p.added_mass_height;
}

// Linear springs, stiff tyres, linear dampers that settle a step within seconds.
FullCarParameters stiffLinear(FullCarParameters p) {
  p.spring_cubic[0] = p.spring_cubic[1] = 0.0;
  p.tyre_stiffness = 1e8;
  p.damper = DamperLaw::kLinear;
  p.damping[0] = p.damping[1] = 6000.0;
  return p;
}

class FlatRoad : public ContactRoad {
 public:
  int contactCount() const override { return 4; }
  void heights(double, Eigen::Ref<Eigen::VectorXd> out) const override { out.setZero(); }
  std::vector<double> breakpoints(double, double) const override { return {}; }
};

std::shared_ptr<const ContactRoad> driving(double a_x, double a_y,
                                           std::shared_ptr<const ContactRoad> road =
                                               std::make_shared<FlatRoad>()) {
  HorizontalState s;
  s.speed = 20.0;
  s.lateral = a_y;
  s.yaw_rate = a_y / s.speed;
  s.longitudinal = a_x;
  return std::make_shared<RoadWithMotion>(std::move(road), std::make_shared<SteadyMotion>(s));
}

// Spring-plus-bar loads from the solved compressions (not the solver's).
void loadsFromCompressions(const FullCarParameters& p, const FullCarEquilibrium& e, double w[4]) {
  for (int c = 0; c < 4; ++c) {
    const int axle = FullCarParameters::axle(c);
    const double d = e.spring_compression[c];
    w[c] = p.spring_linear[axle] * d + p.spring_cubic[axle] * d * d * d +
           p.anti_roll_bar[axle] * (d - e.spring_compression[c ^ 1]);
  }
}

// Cubic springs, heights and bars: the three body equations and the four
// wheels' hold at the solved rest; the heights tilt the body further.
TEST(FullCarHeights, StaticEquilibriumEquationsHold) {
  const FullCarParameters p = elevated();
  const FullCarEquilibrium e = solveFullCarEquilibrium(p);
  double w[4];
  loadsFromCompressions(p, e, w);
  const double g = p.gravity, s = firstMoment(p);
  double force = 0.0, pitch = 0.0, roll = 0.0;
  for (int c = 0; c < 4; ++c) {
    force += w[c];
    pitch += w[c] * p.cornerX(c);
    roll += w[c] * p.cornerY(c);
    EXPECT_NEAR(e.load[c], w[c], 1e-9);
    const int axle = FullCarParameters::axle(c);
    EXPECT_NEAR(w[c] + p.unsprung_mass[axle] * g, -p.tyre_stiffness * e.wheel_height[c], 1e-8);
    // The corner plane: delta_c = zu_c - (z_s + x_c theta_s + y_c phi_s).
    EXPECT_NEAR(e.spring_compression[c],
                e.wheel_height[c] - (e.heave + p.cornerX(c) * e.pitch + p.cornerY(c) * e.roll),
                1e-15);
  }
  EXPECT_NEAR(force, g * (p.body_mass + p.added_mass), 1e-8);
  EXPECT_NEAR(pitch, g * (p.added_mass * p.addedMassX() - s * e.pitch), 1e-8);
  EXPECT_NEAR(roll, g * (p.added_mass * p.addedMassY() - s * e.roll), 1e-8);
  // The elevated masses' weight shifts with the tilt: larger static angles.
  FullCarParameters low = p;
  low.body_cg_height = low.added_mass_height = 0.0;
  const FullCarEquilibrium flat = solveFullCarEquilibrium(low);
  EXPECT_GT(std::abs(e.pitch), std::abs(flat.pitch));
  EXPECT_GT(std::abs(e.roll), std::abs(flat.roll));
  // The bars stiffen the roll; the pitch barely moves (the cubic springs
  // couple them a little).
  low.anti_roll_bar[0] = low.anti_roll_bar[1] = 0.0;
  const FullCarEquilibrium soft = solveFullCarEquilibrium(low);
  EXPECT_GT(std::abs(soft.roll), 1.2 * std::abs(flat.roll));
  EXPECT_NEAR(soft.pitch, flat.pitch, 1e-3 * std::abs(flat.pitch));
}

// The equilibrium is a rest state of the equations of motion with heights
// and bars (the S g tan terms balance the S g sin ones), readings included.
TEST(FullCarHeights, RestStaysAtRest) {
  const FullCarParameters p = elevated();
  const FullCarModel m(p, driving(0.0, 0.0), {ZeroConvention::kRest, true});
  const auto batch = m.prepare(p.toVector());
  const Eigen::ArrayXXd y = batch->initialState();
  Eigen::ArrayXXd d;
  batch->derivatives(0.3, y.topRows(14), d);
  EXPECT_LT(d.abs().maxCoeff(), 1e-10);
  for (int r = kU; r <= kAccelX; ++r) EXPECT_NEAR(y(r, 0), 0.0, 1e-12) << "row " << r;
  EXPECT_EQ(y(kSpeed, 0), 20.0);
  EXPECT_EQ(y(kGyroZ, 0), 0.0);
}

// The body's roll against the axles (from the extensions), and its pitch.
double relativeRoll(const Eigen::ArrayXXd& y, double w) {
  return 0.5 * ((y(kU, 0) - y(kU + 1, 0)) + (y(kU + 2, 0) - y(kU + 3, 0))) / w;
}

// Linear springs, stiff tyres, a steady turn: the roll against the axles
// settles at S a_y / (K_phi - S g) with K_phi = (k_f + k_r) w^2 / 2 +
// (k_a,f + k_a,r) w^2 (each axle's two springs at +-w/2, each bar twisted by
// w phi and acting at +-w/2).
TEST(FullCarHeights, SteadyTurnRollClosedForm) {
  for (const double bar_front : {10000.0, 0.0}) {
    FullCarParameters p = stiffLinear(elevated());
    p.added_mass_y = 0.75;  // on the centre line: no static roll
    p.anti_roll_bar[0] = bar_front;
    const double a_y = 0.5;
    const FullCarModel m(p, driving(0.0, a_y), {ZeroConvention::kRest, true});
    const auto batch = m.prepare(p.toVector());
    Eigen::ArrayXXd y = batch->initialState();
    integrate(m, *batch, 0.0, 6.0, y, IntegratorSettings{5e-4, IntegrationMethod::kRk4});
    const double w = p.track_width, s = firstMoment(p);
    const double k_phi = (p.spring_linear[0] + p.spring_linear[1]) * w * w / 2.0 +
                         (p.anti_roll_bar[0] + p.anti_roll_bar[1]) * w * w;
    const double expected = s * a_y / (k_phi - s * p.gravity);
    const double roll = relativeRoll(y, w);
    EXPECT_GT(roll, 0.0);  // a left turn: the body rolls out of it, left side up
    EXPECT_NEAR(roll, expected, 1e-3 * expected) << "k_a,f = " << bar_front;
    EXPECT_NEAR(y(kPhi, 0), roll, 2e-3 * roll);  // stiff tyres: the axles barely roll
  }
}

// Steady braking: the pitch against the axles settles at
// S a_x / (K_theta - S g), K_theta = sum k x^2 - (sum k x)^2 / sum k (the
// springs' pitch stiffness about their elastic centre: heave and pitch couple
// when k_f a != k_r b); the bars do not act in pitch. Nose down (theta < 0).
TEST(FullCarHeights, SteadyBrakingPitchClosedForm) {
  FullCarParameters p = stiffLinear(elevated());
  p.added_mass_y = 0.75;
  const double a_x = -4.0;
  const FullCarModel m(p, driving(a_x, 0.0), {ZeroConvention::kRest, true});
  const auto batch = m.prepare(p.toVector());
  Eigen::ArrayXXd y = batch->initialState();
  integrate(m, *batch, 0.0, 6.0, y, IntegratorSettings{5e-4, IntegrationMethod::kRk4});
  double sk = 0.0, skx = 0.0, skxx = 0.0;
  for (int c = 0; c < 4; ++c) {
    const double k = p.spring_linear[FullCarParameters::axle(c)], x = p.cornerX(c);
    sk += k;
    skx += k * x;
    skxx += k * x * x;
  }
  const double s = firstMoment(p);
  const double expected = s * a_x / (skxx - skx * skx / sk - s * p.gravity);
  const double pitch = y(kTheta, 0);
  EXPECT_LT(pitch, 0.0);  // braking dives the nose
  EXPECT_NEAR(pitch, expected, 2e-3 * std::abs(expected));
  // The accelerometer reads the deceleration tilted by the pitch:
  // accel_x = a_x + g theta (rest zero: less g theta_s), the dive added.
  EXPECT_NEAR(y(kAccelX, 0), a_x + p.gravity * pitch, 1e-6);
}

// The bars: -k_a (u_l - u_r) on the left end of an axle, +k_a (u_l - u_r) on
// the right, the opposite on the unsprung masses; the other axle untouched.
TEST(FullCarHeights, AntiRollBarForceSigns) {
  FullCarParameters p;
  p.added_mass = 0.0;
  p.anti_roll_bar[0] = 10000.0;
  p.anti_roll_bar[1] = 6000.0;
  FullCarParameters none = p;
  none.anti_roll_bar[0] = none.anti_roll_bar[1] = 0.0;
  const auto road = std::make_shared<FlatRoad>();
  for (int axle = 0; axle < 2; ++axle) {
    Eigen::ArrayXXd y = Eigen::ArrayXXd::Zero(14, 1);
    const double du = 0.01;
    y(kZuFl + 2 * axle + 1, 0) = du;  // the right wheel up: u_l - u_r = du
    Eigen::ArrayXXd with_bar, without;
    FullCarModel(p, road).prepare(p.toVector())->derivatives(0.0, y, with_bar);
    FullCarModel(none, road).prepare(none.toVector())->derivatives(0.0, y, without);
    const double force = p.anti_roll_bar[axle] * du, m_u = p.unsprung_mass[axle];
    const int left = 10 + 2 * axle, right = left + 1, other = axle == 0 ? 12 : 10;
    EXPECT_NEAR(with_bar(left, 0) - without(left, 0), force / m_u, 1e-9);
    EXPECT_NEAR(with_bar(right, 0) - without(right, 0), -force / m_u, 1e-9);
    EXPECT_NEAR(with_bar(other, 0) - without(other, 0), 0.0, 1e-12);
    // On the body: no net force; the roll moment -force w pulls the left down.
    const Eigen::Matrix3d mb = FullCarColumn(p.toVector().data()).bodyMass();
    const Eigen::Vector3d acc = mb.inverse() * Eigen::Vector3d(0.0, 0.0, -force * p.track_width);
    for (int r = 0; r < 3; ++r) {
      EXPECT_NEAR(with_bar(7 + r, 0) - without(7 + r, 0), acc[r], 1e-9) << "axle " << axle;
    }
    EXPECT_LT(with_bar(kPhidot, 0), without(kPhidot, 0));
  }
}

// With every new value 0 the general right-hand side (taken whenever a
// horizontal motion is given, here a_x = a_y = 0) is today's: the same drive
// over the bump to round-off, readings included.
TEST(FullCarHeights, ZeroValuesReproduceTodaysModelOnADrive) {
  FullCarParameters p;
  p.imu_x = 0.3;
  p.imu_y = -0.2;
  FullCarBumpSettings s;
  s.wheelbase = p.wheelbase();
  const auto bump = std::make_shared<FullCarBumpRoad>(s);
  const FullCarModel today(p, bump, {ZeroConvention::kRest, true});
  const FullCarModel general(p, driving(0.0, 0.0, bump), {ZeroConvention::kRest, true});
  const auto a = today.prepare(p.toVector());
  const auto b = general.prepare(p.toVector());
  Eigen::ArrayXXd ya = a->initialState(), yb = b->initialState();
  for (int k = 0; k < 10; ++k) {
    integrate(today, *a, 0.1 * k, 0.1 * (k + 1), ya, IntegratorSettings());
    integrate(general, *b, 0.1 * k, 0.1 * (k + 1), yb, IntegratorSettings());
    for (int r = 0; r < kAccelX; ++r) {
      EXPECT_NEAR(ya(r, 0), yb(r, 0), 1e-11 * (1.0 + std::abs(ya(r, 0)))) << "row " << r;
    }
  }
  EXPECT_GT(ya.col(0).head(14).abs().maxCoeff(), 1e-2);  // the bump moved it
}

// A course: 1 s of ISO 8608 road, a brake, a lane change (rough surfaces).
std::vector<CourseSegment> drive() {
  CourseSegment road, brake, lane;
  road.type = CourseSegment::Type::kIso8608;
  road.duration = 1.0;
  road.speed_kmh = 72.0;
  road.iso8608.road_class = 'B';
  brake.type = CourseSegment::Type::kBrake;
  brake.duration = 2.0;
  brake.speed_kmh = 72.0;
  brake.manoeuvre.longitudinal = 5.0;
  brake.manoeuvre.rough = true;
  brake.iso8608.road_class = 'B';
  brake.iso8608.seed = 2;
  lane.type = CourseSegment::Type::kLaneChange;
  lane.duration = 2.0;
  lane.speed_kmh = 36.0;
  lane.manoeuvre.lateral_acceleration = 4.0;
  lane.manoeuvre.rough = true;
  lane.iso8608.road_class = 'B';
  lane.iso8608.seed = 3;
  return {road, brake, lane};
}

// The course's brake: the speed falls at the rate, the distance is its
// integral, and the rear wheels meet the road a wheelbase after the front.
TEST(FullCarHeights, CourseBrakeAndRearWheels) {
  const std::vector<CourseSegment> segments = drive();
  const FullCarCourseRoad road(segments, 2.6);
  const auto* motion = road.horizontalMotion();
  const HorizontalState mid = motion->at(2.0);
  EXPECT_NEAR(mid.speed, 20.0 - 5.0 * 1.0, 1e-12);
  EXPECT_EQ(mid.longitudinal, -5.0);
  EXPECT_EQ(mid.lateral, 0.0);
  const HorizontalState lane = motion->at(3.5);
  EXPECT_EQ(lane.longitudinal, 0.0);
  EXPECT_NEAR(lane.lateral, 4.0 * std::sin(2.0 * M_PI * 0.5 / 2.0), 1e-12);
  EXPECT_NEAR(lane.yaw_rate, lane.lateral / 10.0, 1e-12);
  const CourseMotion course(segments, CourseRoad(segments).boundaries());
  EXPECT_NEAR(course.distance(2.0), 20.0 + 20.0 * 1.0 - 2.5, 1e-12);
  for (double t : {0.5, 1.7, 2.9, 4.2}) {
    const double rear = road.rearTime(t);
    EXPECT_NEAR(course.distance(t) - course.distance(rear), 2.6, 1e-9) << t;
    Eigen::Vector4d now, then;
    road.heights(t, now);
    road.heights(rear, then);
    EXPECT_EQ(now[2], then[0]);
    EXPECT_EQ(now[3], then[1]);
  }
  EXPECT_LT(road.rearTime(0.1), 0.0);  // 2 m driven: the rear wheels not on the course yet
}

// The IMU channels on a rough braking and lane-change drive against finite
// differences of the simulated motion: gyro_x = phi', gyro_y = -theta',
// gyro_z = a_y / V; the IMU's height adds -z_I phi'' to accel_y, -z_I theta''
// to accel_x and -z_I (phi'^2 + theta'^2) to accel_z; accel_x = a_x +
// (g + z'') theta - imu_x theta'^2 (rest zero: less g theta_s).
TEST(FullCarHeights, ImuChannelsAgainstFiniteDifferences) {
  FullCarParameters low = elevated();
  low.imu_height = 0.0;
  low.imu_x = 0.4;
  FullCarParameters high = low;
  high.imu_height = 0.3;
  const auto road = std::make_shared<FullCarCourseRoad>(drive(), low.wheelbase());
  const FullCarModel m_low(low, road, {ZeroConvention::kRest, true});
  const FullCarModel m_high(high, road, {ZeroConvention::kRest, true});
  const auto b_low = m_low.prepare(low.toVector());
  const auto b_high = m_high.prepare(high.toVector());
  const IntegratorSettings is{5e-5, IntegrationMethod::kRk4};
  const FullCarEquilibrium e = solveFullCarEquilibrium(low);
  Eigen::ArrayXXd state = b_low->initialState(), up = b_high->initialState();
  double now = 0.0;
  for (const double t : {1.6, 3.3}) {  // braking; in the lane change
    const double h = 1e-4;
    integrate(m_low, *b_low, now, t - h, state, is);
    integrate(m_high, *b_high, now, t, up, is);
    const Eigen::ArrayXXd before = state;
    Eigen::ArrayXXd at = before;
    integrate(m_low, *b_low, t - h, t, at, is);
    Eigen::ArrayXXd after = at;
    integrate(m_low, *b_low, t, t + h, after, is);
    state = after;
    now = t + h;
    const Eigen::ArrayXXd up_t = up;  // at t
    integrate(m_high, *b_high, t, now, up, is);
    const double theta_rate = (after(kTheta, 0) - before(kTheta, 0)) / (2.0 * h);
    const double phi_rate = (after(kPhi, 0) - before(kPhi, 0)) / (2.0 * h);
    EXPECT_NEAR(at(kGyroX, 0), phi_rate, 1e-6);
    EXPECT_NEAR(at(kGyroY, 0), -theta_rate, 1e-6);
    const double theta_acc = (after(kThetadot, 0) - before(kThetadot, 0)) / (2.0 * h);
    const double phi_acc = (after(kPhidot, 0) - before(kPhidot, 0)) / (2.0 * h);
    const double z_acc = (after(kZdot, 0) - before(kZdot, 0)) / (2.0 * h);
    EXPECT_GT(std::abs(theta_acc) + std::abs(phi_acc), 0.1);
    const HorizontalState drive = road->horizontalMotion()->at(t);
    EXPECT_EQ(at(kSpeed, 0), drive.speed);
    EXPECT_NEAR(at(kGyroZ, 0) * at(kSpeed, 0), drive.lateral, 1e-12);
    const double theta = e.pitch + at(kTheta, 0);
    EXPECT_NEAR(at(kAccelX, 0),
                drive.longitudinal + (low.gravity + z_acc) * theta -
                    low.imu_x * theta_rate * theta_rate - low.gravity * e.pitch,
                1e-5);
    EXPECT_NEAR(up_t(kAccelY, 0) - at(kAccelY, 0), -0.3 * phi_acc, 1e-5);
    EXPECT_NEAR(up_t(kAccelX, 0) - at(kAccelX, 0), -0.3 * theta_acc, 1e-5);
    EXPECT_NEAR(up_t(kAccelZ, 0) - at(kAccelZ, 0),
                -0.3 * (phi_rate * phi_rate + theta_rate * theta_rate), 1e-6);
  }
}

// Road-free: the model on a rough braking and lane-change drive, heights,
// bars and a high IMU; its clean travels, gyros, speed, yaw rate and accel_x
// drive the road-free model, whose IMU outputs match the model's.
TEST(FullCarHeights, RoadFreeReproducesTheModel) {
  for (const ZeroConvention zero : {ZeroConvention::kTare, ZeroConvention::kRest}) {
    const FullCarParameters p = elevated();
    const FullCarModel full(p, std::make_shared<FullCarCourseRoad>(drive(), p.wheelbase()),
                            {zero, true});
    const auto batch = full.prepare(p.toVector());
    Eigen::ArrayXXd y = batch->initialState();
    const IntegratorSettings is{2.5e-4, IntegrationMethod::kRk4};
    const std::vector<std::string> names{"u_fl", "u_fr", "u_rl",  "u_rr",   "v_fl",
                                         "v_fr", "v_rl", "v_rr",  "gyro_x", "gyro_y",
                                         "speed", "gyro_z", "accel_x"};
    const int rows[13] = {14, 15, 16, 17, 18, 19, 20, 21, kGyroX, kGyroY, kSpeed, kGyroZ, kAccelX};
    std::vector<double> times;
    std::vector<std::vector<double>> in(13);
    std::vector<Eigen::Vector4d> imu;
    double t = 0.0;
    for (int k = 1; k <= 1000; ++k) {
      const double tk = k * 0.005;
      integrate(full, *batch, t, tk, y, is);
      t = tk;
      times.push_back(tk);
      for (int c = 0; c < 13; ++c) in[c].push_back(y(rows[c], 0));
      imu.emplace_back(y(kAccelY, 0), y(kAccelZ, 0), y(kGyroX, 0), y(kGyroY, 0));
    }
    const FullCarRoadFreeModel free(p, std::make_shared<ReadingInputs>(names, times, in), zero);
    EXPECT_TRUE(free.channelIsInput(12));
    EXPECT_TRUE(free.channelIsInput(13));
    EXPECT_TRUE(free.channelIsInput(14));
    const auto fb = free.prepare(p.toVector());
    Eigen::Vector4d worst = Eigen::Vector4d::Zero();
    double swing = 0.0;
    for (std::size_t k = 0; k < times.size(); ++k) {
      Eigen::ArrayXXd r = fb->initialState();
      fb->readings(times[k], r);
      for (int c = 0; c < 4; ++c) worst[c] = std::max(worst[c], std::abs(r(c, 0) - imu[k][c]));
      swing = std::max(swing, std::abs(imu[k][0]));
    }
    EXPECT_GT(swing, 3.0);       // the lane change's a_y
    EXPECT_LT(worst[0], 1e-2);   // accel_y: the gyros' integrals by trapezoids
    EXPECT_LT(worst[1], 1e-2);   // accel_z
    EXPECT_LT(worst[2], 3e-3);   // gyro_x: the increment's trapezoid over 5 ms
    EXPECT_LT(worst[3], 3e-3);   // gyro_y
  }
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
