// Nuisance values in the road-free roll plane (docs/method.md §4.12): a
// road's cross-fall beta is gravity's share g sin(beta) along the tilted
// vehicle's y axis, a lateral specific force on the body and the IMU; a
// roll offset (a tilt the gyro never saw, a gyro bias's drift) turns the
// IMU's reading of the suspension's specific force. Both by their closed
// forms at rest, per point (ModelBatch::offsetPoints), and none of it moves
// a reading when the offsets are 0. The truth's cross-fall (CrossFall).
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "pc_ekf/model/horizontal_motion.h"
#include "pc_ekf/model/roll_plane_road_free.h"

namespace pc_ekf {
namespace {

// The vehicle at rest (zero: rest, so the inputs are the loaded
// equilibrium's zeros): 200 samples of still suspension and gyro.
std::shared_ptr<const ReadingInputs> still() {
  std::vector<double> times;
  for (int k = 1; k <= 200; ++k) times.push_back(0.005 * k);
  std::vector<std::vector<double>> in(5, std::vector<double>(times.size(), 0.0));
  return std::make_shared<ReadingInputs>(std::vector<std::string>{"u1", "u2", "v1", "v2", "gyro_x"},
                                         times, in);
}

TEST(CrossFall, TiltsTheImuByItsClosedForm) {
  VehicleParameters p;
  p.added_mass = 280.0;
  p.added_mass_position = 0.9;  // a static roll phi_s of +14 mrad
  const RollPlaneRoadFreeModel model(p, still(), ZeroConvention::kRest);
  const double g = p.gravity;
  const double t = 0.5;
  // Point 0: level; 1: a 2 % cross-fall; 2: -3 %; 3: a roll offset of 10 mrad.
  const Eigen::MatrixXd params = p.toVector().replicate(1, 4);
  auto batch = model.prepare(params);
  Eigen::VectorXd roll(4), lateral(4);
  roll << 0.0, 0.0, 0.0, 0.01;
  lateral << 0.0, g * std::sin(0.02), g * std::sin(-0.03), 0.0;
  ASSERT_TRUE(batch->offsetPoints(roll, lateral));
  Eigen::ArrayXXd y = Eigen::ArrayXXd::Zero(3, 4);
  batch->readings(t, y);
  // Level and at rest: the rest zeros, nothing else.
  EXPECT_NEAR(y(0, 0), 0.0, 1e-9);
  EXPECT_NEAR(y(1, 0), 0.0, 1e-9);
  // On a cross-fall beta: a_y = g sin(beta) in accel_y = a_y cos(phi) +
  // (g + a) sin(phi) and accel_z = (g + a) cos(phi) - a_y phi, at rest (g + a
  // = g, the rest zeros g sin(phi_s), g cos(phi_s) taken off):
  // accel_y = g sin(beta) cos(phi_s), accel_z = -g sin(beta) phi_s, with
  // phi_s the loaded static roll (+14.4 mrad, left side up).
  const double phi_s = -y(1, 1) / (g * std::sin(0.02));
  EXPECT_NEAR(phi_s, 0.0144, 0.001);
  for (int q = 1; q <= 2; ++q) {
    const double beta = q == 1 ? 0.02 : -0.03;
    EXPECT_NEAR(y(0, q), g * std::sin(beta) * std::cos(phi_s), 1e-9) << beta;
    EXPECT_NEAR(y(1, q), -g * std::sin(beta) * phi_s, 1e-9) << beta;
    EXPECT_NEAR(y(2, q), 0.0, 1e-9) << "at rest the gyro sees no cross-fall";
  }
  // The roll offset delta turns the specific force g (at rest):
  // accel_y = g (sin(phi_s + delta) - sin(phi_s)),
  // accel_z = g (cos(phi_s + delta) - cos(phi_s)).
  EXPECT_NEAR(y(0, 3), g * (std::sin(phi_s + 0.01) - std::sin(phi_s)), 1e-9);
  EXPECT_NEAR(y(1, 3), g * (std::cos(phi_s + 0.01) - std::cos(phi_s)), 1e-9);
}

TEST(CrossFall, ZeroOffsetsLeaveTheReadingsBitForBit) {
  VehicleParameters p;
  p.added_mass = 150.0;
  p.added_mass_position = 0.62;
  const RollPlaneRoadFreeModel model(p, still(), ZeroConvention::kTare);
  const Eigen::MatrixXd params = p.toVector();
  auto plain = model.prepare(params);
  auto zeroed = model.prepare(params);
  ASSERT_TRUE(zeroed->offsetPoints(Eigen::VectorXd::Zero(1), Eigen::VectorXd::Zero(1)));
  for (double t : {0.005, 0.3, 1.0}) {
    Eigen::ArrayXXd a = Eigen::ArrayXXd::Zero(3, 1), b = a;
    plain->readings(t, a);
    zeroed->readings(t, b);
    for (int r = 0; r < 3; ++r) EXPECT_EQ(a(r, 0), b(r, 0)) << t << " " << r;
  }
}

TEST(CrossFall, ACrownChangeIsAHalfCosineAndItsRate) {
  CrossFall c;
  c.start = 0.02;
  c.end = -0.02;
  c.at = 10.0;
  c.over = 3.0;
  EXPECT_EQ(c.angle(0.0), 0.02);
  EXPECT_EQ(c.angle(10.0), 0.02);
  EXPECT_NEAR(c.angle(11.5), 0.0, 1e-15);
  EXPECT_EQ(c.angle(13.0), -0.02);
  EXPECT_EQ(c.angle(50.0), -0.02);
  // The rate integrates to the change.
  double sum = 0.0;
  const double h = 1e-4;
  for (double t = 10.0 + 0.5 * h; t < 13.0; t += h) sum += c.rate(t) * h;
  EXPECT_NEAR(sum, -0.04, 1e-8);
  EXPECT_EQ(c.rate(5.0), 0.0);
  // A constant cross-fall (end = start) and its motion: a_y = g sin(beta).
  CrossFall constant;
  constant.start = constant.end = 0.02;
  EXPECT_TRUE(constant.active());
  EXPECT_EQ(constant.angle(100.0), 0.02);
  const CrossFallMotion motion(nullptr, constant, 9.81);
  EXPECT_NEAR(motion.at(3.0).lateral, 9.81 * std::sin(0.02), 1e-15);
  EXPECT_EQ(motion.at(3.0).yaw_rate, 0.0);  // not a turn
  EXPECT_FALSE(CrossFall().active());
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
