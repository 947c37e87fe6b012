// Full-car 7-DOF ride model: static equilibrium, rest, step refinement, the
// linear variant against the matrix exponential, left/right symmetry, the
// bump road and the parameter domain.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <unsupported/Eigen/MatrixFunctions>

#include "pc_ekf/model/full_car_model.h"
#include "pc_ekf/model/full_car_road.h"
#include "pc_ekf/model/integrator.h"

namespace pc_ekf {
namespace {

const int kParameterCount = 28;  // fullCarParameterNames().size()

constexpr double kSpeed = 16.0 / 3.6;

FullCarParameters truth() {
  FullCarParameters p;
  p.added_mass = 200.0 * (1.0 + 0.5 * 0.2326);
  p.added_mass_x = 1.3 * (1.0 + 0.4 * -0.3875);
  p.added_mass_y = 0.75 * (1.0 + 0.25 * 0.3);
  return p;
}

FullCarParameters linearVariant(FullCarParameters p) {
  p.spring_cubic[0] = p.spring_cubic[1] = 0.0;
  p.damper = DamperLaw::kLinear;
  return p;
}

std::shared_ptr<const FullCarBumpRoad> bumpRoad(FullCarBumpSettings s = FullCarBumpSettings()) {
  return std::make_shared<FullCarBumpRoad>(s);
}

// The seven equilibrium equations evaluated from the solved pose and wheel
// heights alone (not from the solver's compressions or loads).
Eigen::Matrix<double, 7, 1> residualsOf(const FullCarParameters& p, const FullCarEquilibrium& e) {
  Eigen::Matrix<double, 7, 1> r;
  const double g = p.gravity, m = p.added_mass;
  r[0] = -g * (p.body_mass + m);
  r[1] = -g * m * (p.added_mass_x - p.rear_axle_distance);
  r[2] = -g * m * (p.added_mass_y - 0.5 * p.track_width);
  const double x[4] = {p.front_axle_distance, p.front_axle_distance, -p.rear_axle_distance,
                       -p.rear_axle_distance};
  const double y[4] = {0.5 * p.track_width, -0.5 * p.track_width, 0.5 * p.track_width,
                       -0.5 * p.track_width};
  for (int i = 0; i < 4; ++i) {
    const int axle = i / 2;
    const double d = e.wheel_height[i] - (e.heave + x[i] * e.pitch + y[i] * e.roll);
    const double f = p.spring_linear[axle] * d + p.spring_cubic[axle] * d * d * d;
    r[0] += f;
    r[1] += f * x[i];
    r[2] += f * y[i];
    r[3 + i] = f + p.unsprung_mass[axle] * g + p.tyre_stiffness * e.wheel_height[i];
  }
  return r;
}

TEST(FullCarParameters, VectorRoundTripAndNames) {
  const FullCarParameters p = truth();
  const Eigen::VectorXd v = p.toVector();
  ASSERT_EQ(v.size(), 28);  // 21, then the heights and bars (all 0 by default)
  ASSERT_EQ(fullCarParameterNames().size(), 28u);
  EXPECT_EQ(fullCarParameterNames().front(), "body_mass");
  EXPECT_EQ(fullCarParameterNames()[20], "imu_y");
  EXPECT_EQ(fullCarParameterNames().back(), "anti_roll_bar_rear");
  EXPECT_EQ(FullCarParameters::fromVector(v, p).toVector(), v);
  const FullCarModel model(p, bumpRoad());
  EXPECT_EQ(model.parameterIndex("tyre_stiffness"), 14);
  EXPECT_DOUBLE_EQ(v[model.parameterIndex("added_mass_x")], 1.3 * (1.0 - 0.4 * 0.3875));
  EXPECT_EQ(model.stateSize(), 14);
  EXPECT_EQ(model.channelNames().size(), 15u);  // 8 suspension, 4 IMU, accel_x speed gyro_z
  EXPECT_EQ(model.observationMatrix().rows(), 15);
  EXPECT_TRUE(model.channelModelled(7));
  EXPECT_FALSE(model.channelModelled(8));  // IMU channels need readings as states
  // H: u_fr = z + a theta - (w/2) phi - zu_fr; v_rl = zdot - b thetadot + (w/2) phidot - zudot_rl.
  const Eigen::MatrixXd& h = model.observationMatrix();
  EXPECT_EQ(h(1, 0), 1.0);
  EXPECT_EQ(h(1, 1), 1.1);
  EXPECT_EQ(h(1, 2), -0.75);
  EXPECT_EQ(h(1, 4), -1.0);
  EXPECT_EQ(h(6, 7), 1.0);
  EXPECT_EQ(h(6, 8), -1.5);
  EXPECT_EQ(h(6, 9), 0.75);
  EXPECT_EQ(h(6, 12), -1.0);
  EXPECT_NEAR(h.cwiseAbs().sum(), 8 * 2 + 4 * (1.1 + 1.5) + 8 * 0.75, 1e-14);
}

TEST(FullCarEquilibrium, ResidualsBelow1e9) {
  std::vector<FullCarParameters> sets = {FullCarParameters(), truth(), linearVariant(truth())};
  FullCarParameters p = truth();
  p.added_mass = 0.0;
  sets.push_back(p);
  p = FullCarParameters();
  p.added_mass = 300.0;  // corner of the domain: over the right rear wheel
  p.added_mass_x = 0.0;
  p.added_mass_y = 0.0;
  sets.push_back(p);
  p.added_mass_x = 2.6;  // over the left front wheel
  p.added_mass_y = 1.5;
  sets.push_back(p);
  p.spring_linear[0] = 5000.0;  // soft and strongly cubic
  p.spring_cubic[1] = 5e6;
  sets.push_back(p);
  p = truth();  // nearly pure cubic: the linear start is far off, the line search works
  p.spring_linear[0] = p.spring_linear[1] = 100.0;
  p.spring_cubic[0] = p.spring_cubic[1] = 1e12;
  sets.push_back(p);
  const std::vector<FullCarEquilibrium> batch = solveFullCarEquilibria(sets);
  ASSERT_EQ(batch.size(), sets.size());
  for (std::size_t j = 0; j < sets.size(); ++j) {
    const FullCarEquilibrium e = solveFullCarEquilibrium(sets[j]);
    const Eigen::Matrix<double, 7, 1> r = residualsOf(sets[j], e);
    std::printf("set %zu: %d iterations, z_s %.6f theta_s %.3e phi_s %.3e, max |residual| %.2e\n",
                j, e.iterations, e.heave, e.pitch, e.roll, r.cwiseAbs().maxCoeff());
    EXPECT_LT(r.cwiseAbs().maxCoeff(), 1e-9) << "set " << j;
    EXPECT_EQ(batch[j].heave, e.heave);
    EXPECT_EQ(batch[j].roll, e.roll);
    double total = 0.0;
    for (int i = 0; i < 4; ++i) total += e.load[i];
    EXPECT_NEAR(total, (sets[j].body_mass + sets[j].added_mass) * 9.81, 1e-9);
  }
}

// The model memoises equilibria by fullCarEquilibriumKey: values the solve
// does not read leave the key (and the equilibrium) as they are; each value
// it reads changes the key.
TEST(FullCarEquilibrium, KeyHoldsWhatTheSolveReads) {
  FullCarParameters base = truth();
  base.body_cg_height = 0.3;
  base.anti_roll_bar[0] = 8000.0;
  const Eigen::VectorXd v0 = base.toVector();
  const FullCarEquilibriumKey k0 = fullCarEquilibriumKey(FullCarColumn(v0.data()));
  const FullCarEquilibrium e0 = solveFullCarEquilibrium(base);

  FullCarParameters unread = base;
  unread.damping[0] *= 1.3;
  unread.damping[1] *= 0.7;
  unread.roll_inertia *= 1.1;
  unread.pitch_inertia *= 0.9;
  const Eigen::VectorXd v1 = unread.toVector();
  EXPECT_TRUE(fullCarEquilibriumKey(FullCarColumn(v1.data())) == k0);
  const FullCarEquilibrium e1 = solveFullCarEquilibrium(unread);
  EXPECT_EQ(e1.heave, e0.heave);
  EXPECT_EQ(e1.pitch, e0.pitch);
  EXPECT_EQ(e1.roll, e0.roll);

  // Each value the solve reads, nudged: a different key and a different pose.
  std::vector<FullCarParameters> read(6, base);
  read[0].spring_linear[1] *= 1.01;
  read[1].anti_roll_bar[0] *= 1.5;
  read[2].added_mass_y *= 1.01;
  read[3].body_cg_height += 0.01;
  read[4].tyre_stiffness *= 1.01;
  read[5].unsprung_mass[0] *= 1.01;
  for (std::size_t i = 0; i < read.size(); ++i) {
    const Eigen::VectorXd v = read[i].toVector();
    EXPECT_FALSE(fullCarEquilibriumKey(FullCarColumn(v.data())) == k0) << "nudge " << i;
    const FullCarEquilibrium e = solveFullCarEquilibrium(read[i]);
    const bool moved = e.heave != e0.heave || e.pitch != e0.pitch || e.roll != e0.roll;
    EXPECT_TRUE(moved) << "nudge " << i;
  }
}

TEST(FullCarEquilibrium, TruthValues) {
  // Printed for comparison with an independent implementation.
  const FullCarParameters p = truth();
  const FullCarEquilibrium e = solveFullCarEquilibrium(p);
  std::printf("truth: z_s %.12f theta_s %.12e phi_s %.12e\n", e.heave, e.pitch, e.roll);
  for (int i = 0; i < 4; ++i) {
    std::printf("  corner %d: zu %.12f delta %.12f load %.9f\n", i, e.wheel_height[i],
                e.spring_compression[i], e.load[i]);
  }
  // From a separate scipy fsolve of the same seven equations (full_car_reference.py).
  EXPECT_NEAR(e.heave, -0.17267450974136103, 1e-12);
  EXPECT_NEAR(e.pitch, -0.015843245885482134, 1e-12);
  EXPECT_NEAR(e.roll, -0.0022382988762504647, 1e-12);
  const double zu[4] = {-0.021463947106607435, -0.02104450171858487, -0.017530913255892563,
                        -0.017129040918915133};
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(e.wheel_height[i], zu[i], 1e-12);
  // M sits behind O (x_M = 1.3 * 0.845 - 1.5 < 0) and left of it: rear and left sink.
  EXPECT_LT(p.addedMassX(), 0.0);
  EXPECT_GT(p.addedMassY(), 0.0);
  EXPECT_LT(e.roll, 0.0);
  EXPECT_GT(e.load[0], e.load[1]);
  EXPECT_GT(e.load[2], e.load[3]);
}

TEST(FullCarEquilibrium, NoAddedMassIsSymmetricWithAxleLoadsByLeverArms) {
  FullCarParameters p = truth();
  p.added_mass = 0.0;
  const FullCarEquilibrium e = solveFullCarEquilibrium(p);
  const double a = p.front_axle_distance, b = p.rear_axle_distance, w = p.body_mass * 9.81;
  EXPECT_NEAR(e.roll, 0.0, 1e-15);
  EXPECT_NEAR(e.load[0] + e.load[1], w * b / (a + b), 1e-9);
  EXPECT_NEAR(e.load[2] + e.load[3], w * a / (a + b), 1e-9);
  EXPECT_NEAR(e.load[0], w * b / (a + b) / 2, 1e-9);
  EXPECT_NEAR(e.load[1], e.load[0], 1e-9);
  EXPECT_NEAR(e.load[3], e.load[2], 1e-9);
  EXPECT_NEAR(e.wheel_height[0], e.wheel_height[1], 1e-15);
  EXPECT_NEAR(e.wheel_height[2], e.wheel_height[3], 1e-15);
  EXPECT_NEAR(e.spring_compression[2], e.spring_compression[3], 1e-15);
  // The front load 1200 * 9.81 * 1.5 / 2.6 = 6791.54 N on cubic springs.
  const double d = e.spring_compression[0];
  EXPECT_NEAR(20000.0 * d + 1e5 * d * d * d, 1200.0 * 9.81 * 1.5 / 2.6 / 2, 1e-9);
  // theta_s follows from the corner heights (zu - delta) front and rear.
  const double zf = e.wheel_height[0] - e.spring_compression[0];
  const double zr = e.wheel_height[2] - e.spring_compression[2];
  EXPECT_NEAR(e.pitch, (zf - zr) / (a + b), 1e-15);
}

TEST(FullCarEquilibrium, LinearSpringsOffCentreMatchIndependentLoadSplit) {
  // k3 = 0: the loads F_i solve force balance, both moments and the
  // compatibility condition that the four corners z_i = zu_i - delta_i, with
  // zu_i = -(F_i + m_u g) / k_t and delta_i = F_i / k_i, lie on one plane
  // (z_fl - z_fr - z_rl + z_rr = 0 for the rectangle). Solved here directly.
  FullCarParameters p = linearVariant(truth());
  p.added_mass = 300.0;
  p.added_mass_y = 0.2;  // far right, so the split depends on the stiffnesses
  const FullCarEquilibrium e = solveFullCarEquilibrium(p);
  const double g = p.gravity, kt = p.tyre_stiffness;
  Eigen::Matrix4d a;
  Eigen::Vector4d rhs;
  const double sign[4] = {1.0, -1.0, -1.0, 1.0};
  double constant = 0.0;
  for (int i = 0; i < 4; ++i) {
    a(0, i) = 1.0;
    a(1, i) = p.cornerX(i);
    a(2, i) = p.cornerY(i);
    const int axle = i / 2;
    a(3, i) = sign[i] * (-1.0 / kt - 1.0 / p.spring_linear[axle]);
    constant += sign[i] * (-p.unsprung_mass[axle] * g / kt);
  }
  rhs << (p.body_mass + p.added_mass) * g, p.added_mass * p.addedMassX() * g,
      p.added_mass * p.addedMassY() * g, -constant;
  const Eigen::Vector4d want = a.fullPivLu().solve(rhs);
  double corner[4];
  for (int i = 0; i < 4; ++i) {
    std::printf("corner %d: load %.9f, independent %.9f\n", i, e.load[i], want[i]);
    EXPECT_NEAR(e.load[i], want[i], 1e-9 * want.cwiseAbs().maxCoeff());
    const int axle = i / 2;
    corner[i] = -(e.load[i] + p.unsprung_mass[axle] * g) / kt - e.load[i] / p.spring_linear[axle];
  }
  EXPECT_NEAR(corner[0] - corner[1] - corner[2] + corner[3], 0.0, 1e-14);
  // The split is not the statically determinate one a rigid tyre/spring ratio
  // would give: left and right of each axle differ.
  EXPECT_GT(std::abs(e.load[0] - e.load[1]), 100.0);
  double force = 0.0, pitch = 0.0, roll = 0.0;
  for (int i = 0; i < 4; ++i) {
    force += e.load[i];
    pitch += e.load[i] * p.cornerX(i);
    roll += e.load[i] * p.cornerY(i);
  }
  EXPECT_NEAR(force, (p.body_mass + p.added_mass) * g, 1e-9);
  EXPECT_NEAR(pitch, p.added_mass * p.addedMassX() * g, 1e-9);
  EXPECT_NEAR(roll, p.added_mass * p.addedMassY() * g, 1e-9);
  // And the pose agrees with those corners.
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(e.heave + p.cornerX(i) * e.pitch + p.cornerY(i) * e.roll, corner[i], 1e-14);
  }
}

// Channels at t = 0.3, 0.6, ..., 3.0, integrated sample to sample. (8 * 10) x Q.
Eigen::MatrixXd sampledChannels(const FullCarModel& model, const Eigen::MatrixXd& params,
                                const IntegratorSettings& settings,
                                Eigen::ArrayXXd* final_state = nullptr) {
  const auto batch = model.prepare(params);
  Eigen::ArrayXXd y = batch->initialState();
  Eigen::MatrixXd z(80, params.cols());
  for (int k = 0; k < 10; ++k) {
    integrate(model, *batch, 0.3 * k, 0.3 * (k + 1), y, settings);
    z.middleRows(8 * k, 8) = model.observationMatrix() * y.matrix();
  }
  if (final_state) *final_state = y;
  return z;
}

double channelMax(const Eigen::MatrixXd& z, int c, int q) {
  double s = 0.0;
  for (int k = 0; k < 10; ++k) s = std::max(s, std::abs(z(8 * k + c, q)));
  return s;
}

double channelDiff(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, int c, int q) {
  double d = 0.0;
  for (int k = 0; k < 10; ++k) d = std::max(d, std::abs(a(8 * k + c, q) - b(8 * k + c, q)));
  return d;
}

Eigen::MatrixXd offCentreColumns() {
  FullCarParameters far;
  far.added_mass = 300.0;
  far.added_mass_x = 0.2;
  far.added_mass_y = 0.1;
  Eigen::MatrixXd params(kParameterCount, 3);
  params.col(0) = FullCarParameters().toVector();
  params.col(1) = truth().toVector();
  params.col(2) = far.toVector();
  return params;
}

TEST(FullCarDynamics, FlatRoadKeepsEquilibriumExactly) {
  FullCarBumpSettings flat;
  flat.bump.height_left = flat.bump.height_right = 0.0;  // kinks still there, heights zero
  const FullCarModel model(truth(), bumpRoad(flat));
  Eigen::ArrayXXd y;
  const Eigen::MatrixXd z = sampledChannels(model, offCentreColumns(), IntegratorSettings(), &y);
  for (Eigen::Index i = 0; i < y.size(); ++i) EXPECT_EQ(y(i), 0.0);
  for (Eigen::Index i = 0; i < z.size(); ++i) EXPECT_EQ(z(i), 0.0);
}

TEST(FullCarDynamics, BumpConvergesUnderStepRefinement) {
  const FullCarModel model(FullCarParameters(), bumpRoad());
  const Eigen::MatrixXd params = offCentreColumns();
  const IntegratorSettings fine{1e-4, IntegrationMethod::kRk4};
  const IntegratorSettings rk4{1e-3, IntegrationMethod::kRk4};
  const IntegratorSettings dp5{3e-3, IntegrationMethod::kDormandPrince5};
  const IntegratorSettings rk4_half{5e-4, IntegrationMethod::kRk4};
  const Eigen::MatrixXd z_fine = sampledChannels(model, params, fine);
  const Eigen::MatrixXd z_rk4 = sampledChannels(model, params, rk4);
  const Eigen::MatrixXd z_rk4_half = sampledChannels(model, params, rk4_half);
  const Eigen::MatrixXd z_dp5 = sampledChannels(model, params, dp5);
  ASSERT_TRUE(z_fine.allFinite());
  double worst_rk4 = 0.0, worst_dp5 = 0.0;
  for (int q = 0; q < params.cols(); ++q) {
    for (int c = 0; c < 8; ++c) {
      const double scale = channelMax(z_fine, c, q);
      ASSERT_GT(scale, c < 4 ? 1e-3 : 1e-2) << "channel " << c;  // the bump excites it
      const double e_rk4 = channelDiff(z_rk4, z_fine, c, q) / scale;
      const double e_half = channelDiff(z_rk4_half, z_fine, c, q) / scale;
      const double e_dp5 = channelDiff(z_dp5, z_fine, c, q) / scale;
      std::printf(
          "point %d %s: max %.4g, relative error rk4 1 ms %.2e, 0.5 ms %.2e (ratio %.1f), "
          "dp5 3 ms %.2e\n",
          q, model.channelNames()[c].c_str(), scale, e_rk4, e_half, e_rk4 / e_half, e_dp5);
      EXPECT_LT(e_rk4, 1e-6);
      EXPECT_LT(e_dp5, 1e-6);
      EXPECT_NEAR(e_rk4 / e_half, 16.0, 4.0);  // fourth order
      worst_rk4 = std::max(worst_rk4, e_rk4);
      worst_dp5 = std::max(worst_dp5, e_dp5);
    }
  }
  std::printf("worst relative error: rk4 1 ms %.2e, dp5 3 ms %.2e\n", worst_rk4, worst_dp5);
}

TEST(FullCarDynamics, TruthBumpResponseMatchesSeparateReference) {
  // Channels at t = 0.3, 1.5 and 3 s from a separate numpy implementation of
  // the same equations (full_car_reference.py: scipy DOP853, rtol 1e-13,
  // restarted at every kink).
  const double want[3][8] = {
      {-0.006517646159082735, -0.01148796081914024, 0.015609368256010942, -0.026030324701126085,
       0.30167712848083306, 0.12204766229098946, -0.021603189133061272, 0.025267856630915877},
      {0.004160089064359086, -0.005355866943130064, -0.022491779369897644, -0.03134310570484583,
       -0.18532486854394228, -0.33788557892567794, 0.024920927201680064, -0.1435441315826982},
      {-0.0005167156286507309, -0.0003851326119831293, 0.00029071214483869805,
       0.00042355327331238695, -0.024757727401694005, -0.02586689977474375, -0.01301576842268678,
       -0.014115684515792674}};
  const double scale[8] = {0.0536, 0.0681, 0.0317, 0.0313, 0.302, 0.338, 0.242, 0.193};
  const FullCarModel model(FullCarParameters(), bumpRoad());
  const Eigen::MatrixXd z =
      sampledChannels(model, truth().toVector(), IntegratorSettings{1e-4, IntegrationMethod::kRk4});
  double worst = 0.0;
  const int samples[3] = {0, 4, 9};
  for (int k = 0; k < 3; ++k) {
    for (int c = 0; c < 8; ++c) {
      const double error = std::abs(z(8 * samples[k] + c, 0) - want[k][c]) / scale[c];
      EXPECT_LT(error, 1e-9) << "sample " << samples[k] << " channel " << c;
      worst = std::max(worst, error);
    }
  }
  std::printf("worst difference to the separate reference: %.2e of the channel's range\n", worst);
}

// Sines under the four contacts, each with its own amplitude and phase.
class FourSineRoad : public ContactRoad {
 public:
  static constexpr double kOmega = 2.0 * 3.14159265358979323846 * 1.5;
  static constexpr double kAmplitude[4] = {0.02, 0.015, 0.018, 0.012};
  static constexpr double kPhase[4] = {0.0, 0.7, 1.9, 2.6};
  int contactCount() const override { return 4; }
  void heights(double t, Eigen::Ref<Eigen::VectorXd> out) const override {
    for (int c = 0; c < 4; ++c) out[c] = kAmplitude[c] * std::sin(kOmega * t + kPhase[c]);
  }
  std::vector<double> breakpoints(double, double) const override { return {}; }
};

// The linear variant about the equilibrium, with the sine oscillator
// [sin wt, cos wt] appended as states 14 and 15, built from the equations of
// motion (not from the model's code).
Eigen::Matrix<double, 16, 16> augmentedSystem(const FullCarParameters& p) {
  Eigen::Matrix<double, 16, 16> a = Eigen::Matrix<double, 16, 16>::Zero();
  a.block<7, 7>(0, 7).setIdentity();
  const double m = p.added_mass, xm = p.addedMassX(), ym = p.addedMassY();
  Eigen::Matrix3d mb;
  mb << p.body_mass + m, m * xm, m * ym, m * xm, p.pitch_inertia + m * xm * xm, m * xm * ym, m * ym,
      m * xm * ym, p.roll_inertia + m * ym * ym;
  Eigen::Matrix<double, 3, 16> gen = Eigen::Matrix<double, 3, 16>::Zero();
  for (int i = 0; i < 4; ++i) {
    const int axle = i / 2;
    const double x = p.cornerX(i), y = p.cornerY(i);
    Eigen::Matrix<double, 1, 16> f = Eigen::Matrix<double, 1, 16>::Zero();
    for (int rate = 0; rate < 2; ++rate) {
      const double gain = rate == 0 ? p.spring_linear[axle] : p.damping[axle];
      f(7 * rate) -= gain;
      f(7 * rate + 1) -= gain * x;
      f(7 * rate + 2) -= gain * y;
      f(7 * rate + 3 + i) += gain;
    }
    gen.row(0) += f;
    gen.row(1) += x * f;
    gen.row(2) += y * f;
    const double mu = p.unsprung_mass[axle], kt = p.tyre_stiffness;
    a.row(10 + i) = -f / mu;
    a(10 + i, 3 + i) -= kt / mu;
    // road = A (sin wt cos ph + cos wt sin ph)
    a(10 + i, 14) += kt / mu * FourSineRoad::kAmplitude[i] * std::cos(FourSineRoad::kPhase[i]);
    a(10 + i, 15) += kt / mu * FourSineRoad::kAmplitude[i] * std::sin(FourSineRoad::kPhase[i]);
  }
  a.block<3, 16>(7, 0) = mb.inverse() * gen;
  a(14, 15) = FourSineRoad::kOmega;
  a(15, 14) = -FourSineRoad::kOmega;
  return a;
}

void expectMatchesExponential(const FullCarParameters& p, const char* label) {
  const FullCarModel model(p, std::make_shared<FourSineRoad>());
  const auto batch = model.prepare(p.toVector());
  Eigen::ArrayXXd y = batch->initialState();
  // Exact propagator over one sample interval, applied sample to sample.
  const Eigen::Matrix<double, 16, 16> step = (augmentedSystem(p) * 0.3).exp();
  Eigen::Matrix<double, 16, 1> exact = Eigen::Matrix<double, 16, 1>::Zero();
  exact[15] = 1.0;  // cos(0)
  Eigen::Matrix<double, 14, 10> got, want;
  for (int k = 0; k < 10; ++k) {
    integrate(model, *batch, 0.3 * k, 0.3 * (k + 1), y,
              IntegratorSettings{1e-4, IntegrationMethod::kRk4});
    exact = step * exact;
    got.col(k) = y.matrix();
    want.col(k) = exact.head<14>();
  }
  EXPECT_NEAR(exact[14], std::sin(FourSineRoad::kOmega * 3.0), 1e-12);
  double worst = 0.0;
  for (int s = 0; s < 14; ++s) {
    const double scale = want.row(s).cwiseAbs().maxCoeff();
    ASSERT_GT(scale, 1e-6) << model.stateNames()[s];  // every state responds
    const double error = (got.row(s) - want.row(s)).cwiseAbs().maxCoeff() / scale;
    std::printf("%s %-9s max %.3e, relative error %.2e\n", label, model.stateNames()[s].c_str(),
                scale, error);
    EXPECT_LT(error, 1e-8) << model.stateNames()[s];
    worst = std::max(worst, error);
  }
  std::printf("%s: worst relative error %.2e\n", label, worst);
}

TEST(FullCarLinearVariant, MatchesMatrixExponentialAtNominal) {
  expectMatchesExponential(linearVariant(FullCarParameters()), "nominal");
}

TEST(FullCarLinearVariant, MatchesMatrixExponentialAtTruth) {
  expectMatchesExponential(linearVariant(truth()), "truth");
}

TEST(FullCarDynamics, CentredMassOnSymmetricBumpNeverRolls) {
  FullCarBumpSettings s;
  s.bump.height_left = s.bump.height_right = 0.1;
  s.bump.delay_fraction = 0.0;
  const FullCarModel model(FullCarParameters(), bumpRoad(s));
  Eigen::MatrixXd params(kParameterCount, 2);
  FullCarParameters p;
  p.added_mass_y = 0.75;  // on the centre line
  params.col(0) = p.toVector();
  p.added_mass = 300.0;
  p.added_mass_x = 0.3;
  params.col(1) = p.toVector();
  const auto batch = model.prepare(params);
  Eigen::ArrayXXd y = batch->initialState();
  double worst = 0.0, heave = 0.0, pitch = 0.0, wheel = 0.0;
  for (int k = 0; k < 30; ++k) {
    integrate(model, *batch, 0.1 * k, 0.1 * (k + 1), y, IntegratorSettings());
    for (int q = 0; q < 2; ++q) {
      for (int rate = 0; rate < 2; ++rate) {
        const int o = 7 * rate;
        worst = std::max({worst, std::abs(y(o + 2, q)), std::abs(y(o + 3, q) - y(o + 4, q)),
                          std::abs(y(o + 5, q) - y(o + 6, q))});
      }
      heave = std::max(heave, std::abs(y(0, q)));
      pitch = std::max(pitch, std::abs(y(1, q)));
      wheel = std::max(wheel, std::abs(y(3, q)));
    }
  }
  std::printf(
      "max |z| %.3e, |theta| %.3e, |zu_fl| %.3e; worst roll or left-right difference %.2e\n", heave,
      pitch, wheel, worst);
  EXPECT_GT(heave, 1e-2);
  EXPECT_GT(pitch, 1e-3);
  EXPECT_LT(worst, 1e-13);
}

TEST(FullCarDynamics, MirroredMassMirrorsTheResponse) {
  // M at y and at w - y on a road mirrored left/right: roll and the left/right
  // states swap sign and place.
  FullCarBumpSettings s;
  s.bump.delay_fraction = 0.0;
  s.bump.height_left = s.bump.height_right = 0.08;
  const FullCarModel model(FullCarParameters(), bumpRoad(s));
  Eigen::MatrixXd params(kParameterCount, 2);
  FullCarParameters p = truth();
  params.col(0) = p.toVector();
  p.added_mass_y = p.track_width - p.added_mass_y;
  params.col(1) = p.toVector();
  Eigen::ArrayXXd y;
  sampledChannels(model, params, IntegratorSettings(), &y);
  EXPECT_GT(std::abs(y(2, 0)), 1e-6);
  const int mirror[14] = {0, 1, 2, 4, 3, 6, 5, 7, 8, 9, 11, 10, 13, 12};
  for (int i = 0; i < 14; ++i) {
    const double sign = i == 2 || i == 9 ? -1.0 : 1.0;
    EXPECT_NEAR(y(i, 0), sign * y(mirror[i], 1), 1e-12 * y.abs().maxCoeff())
        << model.stateNames()[i];
  }
}

// The model's batch without its transposed form: integrate() then uses derivatives().
class PlainOnly : public ModelBatch {
 public:
  explicit PlainOnly(const ModelBatch& b) : b_(b) {}
  int pointCount() const override { return b_.pointCount(); }
  void derivatives(double t, const Eigen::ArrayXXd& y, Eigen::ArrayXXd& dydt) const override {
    b_.derivatives(t, y, dydt);
  }
  Eigen::ArrayXXd initialState() const override { return b_.initialState(); }

 private:
  const ModelBatch& b_;
};

Eigen::MatrixXd spreadColumns(int count, DamperLaw law) {
  Eigen::MatrixXd params(kParameterCount, count);
  for (int q = 0; q < count; ++q) {
    FullCarParameters p = truth();
    const double s = static_cast<double>(q) / count;  // 0 .. 1
    p.added_mass = 50.0 + 250.0 * s;
    p.added_mass_x = 2.6 * s;
    p.added_mass_y = 1.5 * (1.0 - s);
    p.damping[1] *= 0.8 + 0.4 * s;
    p.spring_linear[0] *= 1.2 - 0.4 * s;
    p.spring_cubic[1] = law == DamperLaw::kLinear ? 0.0 : 1e5 * (1.0 + s);
    params.col(q) = p.toVector();
  }
  return params;
}

TEST(FullCarDynamics, TransposedDerivativesEqualPlain) {
  for (DamperLaw law : {DamperLaw::kTanh, DamperLaw::kLinear}) {
    FullCarParameters nominal;
    nominal.damper = law;
    const FullCarModel model(nominal, bumpRoad());
    const int n = 37;  // not a multiple of the vector width: the remainder loop too
    const auto batch = model.prepare(spreadColumns(n, law));
    ASSERT_TRUE(batch->hasTransposedDerivatives());
    // Derivatives at arbitrary states (large rates: both tanh branches).
    Eigen::ArrayXXd y = Eigen::ArrayXXd::Random(14, n) * 0.05;
    y.bottomRows(7) *= 20.0;
    Eigen::ArrayXXd plain, transposed;
    double worst = 0.0;
    for (double t : {0.1, 0.4, 0.9}) {
      batch->derivatives(t, y, plain);
      batch->derivativesTransposed(t, y.transpose(), transposed);
      ASSERT_EQ(transposed.rows(), n);
      for (int i = 0; i < 14; ++i) {
        const double scale = plain.row(i).abs().maxCoeff();
        ASSERT_GT(scale, 0.0);
        worst = std::max(worst,
                         (transposed.col(i).transpose() - plain.row(i)).abs().maxCoeff() / scale);
      }
    }
    // Integrated over the bump, the two layouts agree to rounding.
    const PlainOnly plain_batch(*batch);
    Eigen::ArrayXXd y_soa = batch->initialState(), y_plain = plain_batch.initialState();
    const IntegratorSettings settings{1e-3, IntegrationMethod::kRk4};
    integrate(model, *batch, 0.0, 3.0, y_soa, settings);
    integrate(model, plain_batch, 0.0, 3.0, y_plain, settings);
    const double integrated = (y_soa - y_plain).abs().maxCoeff() / y_plain.abs().maxCoeff();
    std::printf("%s: derivatives differ by %.2e, states after 3 s by %.2e (relative)\n",
                law == DamperLaw::kTanh ? "tanh" : "linear", worst, integrated);
    EXPECT_LT(worst, 1e-14);
    EXPECT_LT(integrated, 1e-12);
    // And each column alone gives what it gives in the batch.
    double alone = 0.0;
    for (int q : {0, 5, n - 1}) {
      const Eigen::MatrixXd column = spreadColumns(n, law).col(q);
      const auto single = model.prepare(column);
      Eigen::ArrayXXd y1 = single->initialState();
      integrate(model, *single, 0.0, 3.0, y1, settings);
      alone = std::max(alone,
                       (y1.col(0) - y_soa.col(q)).abs().maxCoeff() / y_soa.col(q).abs().maxCoeff());
    }
    std::printf("  single column against the batch: %.2e\n", alone);
    EXPECT_LT(alone, 1e-12);
  }
}

TEST(FullCarBumpRoad, HeightsAndKinks) {
  const FullCarBumpRoad road{FullCarBumpSettings()};
  EXPECT_EQ(road.contactCount(), 4);
  Eigen::VectorXd h(4);
  const auto at_travel = [&](double d) {
    road.heights(d / kSpeed, h);
    return Eigen::Vector4d(h);
  };
  // Travel 0.5: front left half up, front right not there yet.
  Eigen::Vector4d v = at_travel(0.5);
  EXPECT_NEAR(v[0], 0.05, 1e-15);
  EXPECT_EQ(v[1], 0.0);
  // Travel 1.5: front left on the top, front right 0.9 m up its ramp.
  v = at_travel(1.5);
  EXPECT_NEAR(v[0], 0.10, 1e-15);
  EXPECT_NEAR(v[1], 0.08 * 0.9, 1e-15);
  // Travel 3.35: front left off, front right coming down (0.25 left), rear
  // left 0.75 up its ramp, rear right (from 3.2) 0.15 up.
  v = at_travel(3.35);
  EXPECT_EQ(v[0], 0.0);
  EXPECT_NEAR(v[1], 0.08 * 0.25, 1e-14);
  EXPECT_NEAR(v[2], 0.10 * 0.75, 1e-14);
  EXPECT_NEAR(v[3], 0.08 * 0.15, 1e-14);
  EXPECT_EQ(at_travel(3.1)[3], 0.0);
  // Travel 6.4 (2.6 + 0.6 + 3 = 6.2): everything past.
  EXPECT_EQ(at_travel(6.4).cwiseAbs().sum(), 0.0);
  // Every corner of every wheel, in order.
  const std::vector<double> kinks = road.breakpoints(0.0, 10.0);
  std::vector<double> want;
  for (double offset : {0.0, 0.6, 2.6, 3.2}) {
    for (double corner : {0.0, 1.0, 2.0, 3.0}) {
      if (offset + corner > 0.0) want.push_back((offset + corner) / kSpeed);
    }
  }
  std::sort(want.begin(), want.end());
  // 2.6 and 3.6 m are corners of two wheels each (front right, rear left).
  want.erase(std::unique(want.begin(), want.end(),
                         [](double x, double y) { return std::abs(x - y) < 1e-12; }),
             want.end());
  ASSERT_EQ(want.size(), 13u);
  ASSERT_EQ(kinks.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i) EXPECT_NEAR(kinks[i], want[i], 1e-14);
  // Open interval: the kinks at 1 and 2 m are its ends; 1.6 m is inside.
  const std::vector<double> inside = road.breakpoints(1.0 / kSpeed, 2.0 / kSpeed);
  ASSERT_EQ(inside.size(), 1u);
  EXPECT_NEAR(inside[0] * kSpeed, 1.6, 1e-14);
  FullCarBumpSettings bad;
  bad.bump.speed_kmh = 0.0;
  EXPECT_THROW(FullCarBumpRoad{bad}, std::invalid_argument);
  bad = FullCarBumpSettings();
  bad.wheelbase = -1.0;
  EXPECT_THROW(FullCarBumpRoad{bad}, std::invalid_argument);
}

TEST(FullCarModel, RejectsRoadsWithoutFourContacts) {
  class TwoContacts : public ContactRoad {
   public:
    int contactCount() const override { return 2; }
    void heights(double, Eigen::Ref<Eigen::VectorXd> out) const override { out.setZero(); }
    std::vector<double> breakpoints(double, double) const override { return {}; }
  };
  EXPECT_THROW(FullCarModel(FullCarParameters(), std::make_shared<TwoContacts>()),
               std::invalid_argument);
  EXPECT_THROW(FullCarModel(FullCarParameters(), nullptr), std::invalid_argument);
}

TEST(FullCarModel, InvalidReasonForEachDomainRule) {
  const FullCarModel model(FullCarParameters(), bumpRoad());
  const Eigen::VectorXd nominal = model.nominalParameters();
  const auto& names = model.parameterNames();
  EXPECT_EQ(model.invalidReason(nominal), "");
  EXPECT_EQ(model.invalidReason(truth().toVector()), "");
  EXPECT_NE(model.invalidReason(nominal.head(27)).find("expected 28"), std::string::npos);
  const auto reason = [&](int i, double value) {
    Eigen::VectorXd v = nominal;
    v[i] = value;
    return model.invalidReason(v);
  };
  const auto expectContains = [](const std::string& text, const std::string& part) {
    EXPECT_NE(text.find(part), std::string::npos) << "'" << text << "' lacks '" << part << "'";
  };
  for (int i = 0; i < kParameterCount; ++i) {
    expectContains(reason(i, std::numeric_limits<double>::quiet_NaN()), names[i] + " = nan");
    expectContains(reason(i, std::numeric_limits<double>::infinity()), "is not finite");
  }
  for (int i : {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 14, 15}) {
    expectContains(reason(i, 0.0), names[i] + " = 0 must be > 0");
    expectContains(reason(i, -1.0), names[i] + " = -1 must be > 0");
  }
  for (int i : {10, 11, 12, 13, 16}) {
    EXPECT_EQ(reason(i, 0.0), "") << names[i];
    expectContains(reason(i, -0.5), names[i] + " = -0.5 must be >= 0");
  }
  // added_mass_x in [0, a + b], added_mass_y in [0, w]: the ends are admissible.
  EXPECT_EQ(reason(17, 0.0), "");
  EXPECT_EQ(reason(17, 2.6), "");
  expectContains(reason(17, -0.01), "added_mass_x = -0.01 outside [0, 2.6]");
  expectContains(reason(17, 2.61), "added_mass_x = 2.61 outside [0, 2.6]");
  EXPECT_EQ(reason(18, 0.0), "");
  EXPECT_EQ(reason(18, 1.5), "");
  expectContains(reason(18, -0.01), "added_mass_y = -0.01 outside [0, 1.5]");
  expectContains(reason(18, 1.51), "added_mass_y = 1.51 outside [0, 1.5]");
  // The bounds follow the column's own geometry.
  Eigen::VectorXd v = nominal;
  v[5] = 1.2;  // narrower track
  EXPECT_EQ(model.invalidReason(v), "");
  v[18] = 1.3;
  expectContains(model.invalidReason(v), "added_mass_y = 1.3 outside [0, 1.2]");
  v[18] = nominal[18];
  v[5] = 1.5;
  v[3] = 0.8;
  v[17] = 2.5;
  expectContains(model.invalidReason(v), "added_mass_x = 2.5 outside [0, 2.3]");
  // Finite but overflowing: the equilibrium cannot be solved.
  expectContains(reason(0, 1e308), "static equilibrium");
  // prepare() refuses inadmissible columns.
  Eigen::MatrixXd params(kParameterCount, 2);
  params.col(0) = nominal;
  params.col(1) = nominal;
  params(17, 1) = 3.0;
  EXPECT_THROW(model.prepare(params), std::invalid_argument);
  params(17, 1) = nominal[17];
  params(0, 1) = 1e308;
  EXPECT_THROW(model.prepare(params), std::invalid_argument);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
