// Roll-plane dynamics (docs/method.md §1.4, §7): step-refinement convergence, equilibrium
// at rest, batch independence, non-finite columns, cost.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <memory>
#include <random>

#include "pc_ekf/model/integrator.h"
#include "pc_ekf/model/roll_plane_model.h"

namespace pc_ekf {
namespace {

const int kRows = static_cast<int>(rollPlaneDescription().parameters().size());

Eigen::VectorXd paramsAt(const RollPlaneModel& model, double xi1, double xi2) {
  Eigen::VectorXd v = model.nominalParameters();
  v[14] = 200.0 * (1.0 + 0.5 * xi1);
  v[15] = 0.762 * (1.0 + 0.25 * xi2);
  return v;
}

// Channels z = H y at t = 0.3, 0.6, ..., 3.0 (the N = 10 sample times), integrating
// sample to sample as the filters do. Result: (4 * 10) x Q, sample-major.
Eigen::MatrixXd sampledChannels(const RollPlaneModel& model, const Eigen::MatrixXd& params,
                                double max_step, Eigen::ArrayXXd* final_state = nullptr) {
  const auto batch = model.prepare(params);
  Eigen::ArrayXXd y = batch->initialState();
  IntegratorSettings settings;
  settings.max_step = max_step;
  Eigen::MatrixXd z(40, params.cols());
  for (int k = 0; k < 10; ++k) {
    integrate(model, *batch, 0.3 * k, 0.3 * (k + 1), y, settings);
    z.middleRows(4 * k, 4) = model.observationMatrix() * y.matrix();
  }
  if (final_state) *final_state = y;
  return z;
}

// Largest |z| of channel c for point q over the samples.
double channelScale(const Eigen::MatrixXd& z, int c, int q) {
  double s = 0.0;
  for (int k = 0; k < 10; ++k) s = std::max(s, std::abs(z(4 * k + c, q)));
  return s;
}

double channelDiff(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, int c, int q) {
  double d = 0.0;
  for (int k = 0; k < 10; ++k) d = std::max(d, std::abs(a(4 * k + c, q) - b(4 * k + c, q)));
  return d;
}

TEST(RollPlaneDynamics, SpeedBumpConvergesWithFourthOrder) {
  const RollPlaneModel model(VehicleParameters(),
                             std::make_shared<SpeedBumpRoad>(SpeedBumpSettings()));
  Eigen::MatrixXd params(kRows, 3);
  params.col(0) = paramsAt(model, 0.0, 0.0);
  params.col(1) = paramsAt(model, 0.2326, -0.3875);  // docs/method.md §1.6 truth
  params.col(2) = paramsAt(model, 1.0, 1.0);
  const double steps[4] = {2e-3, 1e-3, 5e-4, 2.5e-4};
  Eigen::MatrixXd z[4];
  for (int i = 0; i < 4; ++i) z[i] = sampledChannels(model, params, steps[i]);
  ASSERT_TRUE(z[3].allFinite());
  for (int q = 0; q < 3; ++q) {
    for (int c = 0; c < 4; ++c) {
      const double scale = channelScale(z[3], c, q);
      ASSERT_GT(scale, c < 2 ? 1e-3 : 1e-2);  // the bump really excites every channel
      const double d01 = channelDiff(z[0], z[1], c, q) / scale;
      const double d12 = channelDiff(z[1], z[2], c, q) / scale;
      const double d23 = channelDiff(z[2], z[3], c, q) / scale;
      // Error of the 1e-3 run, Richardson-estimated for a 4th-order method.
      const double error_1e3 = d12 * 16.0 / 15.0;
      std::printf(
          "point %d channel %d: scale %.4g, relative differences %.3e %.3e %.3e, "
          "ratios %.2f %.2f\n",
          q, c, scale, d01, d12, d23, d01 / d12, d12 / d23);
      EXPECT_LT(error_1e3, 1e-6) << "point " << q << " channel " << c;
      EXPECT_LT(d23 * 16.0 / 15.0, 1e-7);
      EXPECT_NEAR(d01 / d12, 16.0, 3.0) << "point " << q << " channel " << c;
      EXPECT_NEAR(d12 / d23, 16.0, 3.0) << "point " << q << " channel " << c;
    }
  }
}

// The fixed-step Dormand-Prince 5 (IntegrationMethod::kDormandPrince5): fifth
// order under refinement, and at a 3 ms step as accurate as RK4 at 1 ms
// (docs/method.md §7: below 1e-6 of each channel's range) with half the evaluations.
Eigen::MatrixXd sampledChannelsDp5(const RollPlaneModel& model, const Eigen::MatrixXd& params,
                                   double max_step) {
  const auto batch = model.prepare(params);
  Eigen::ArrayXXd y = batch->initialState();
  const IntegratorSettings settings{max_step, IntegrationMethod::kDormandPrince5};
  Eigen::MatrixXd z(40, params.cols());
  for (int k = 0; k < 10; ++k) {
    integrate(model, *batch, 0.3 * k, 0.3 * (k + 1), y, settings);
    z.middleRows(4 * k, 4) = model.observationMatrix() * y.matrix();
  }
  return z;
}

TEST(RollPlaneDynamics, DormandPrinceConvergesWithFifthOrder) {
  const RollPlaneModel model(VehicleParameters(),
                             std::make_shared<SpeedBumpRoad>(SpeedBumpSettings()));
  Eigen::MatrixXd params(kRows, 3);
  params.col(0) = paramsAt(model, 0.0, 0.0);
  params.col(1) = paramsAt(model, 0.2326, -0.3875);
  params.col(2) = paramsAt(model, 1.0, 1.0);
  const double steps[4] = {6e-3, 3e-3, 1.5e-3, 7.5e-4};
  Eigen::MatrixXd z[4];
  for (int i = 0; i < 4; ++i) z[i] = sampledChannelsDp5(model, params, steps[i]);
  const Eigen::MatrixXd rk4_fine = sampledChannels(model, params, 1.25e-4);
  for (int q = 0; q < 3; ++q) {
    for (int c = 0; c < 4; ++c) {
      const double scale = channelScale(z[3], c, q);
      const double d01 = channelDiff(z[0], z[1], c, q) / scale;
      const double d12 = channelDiff(z[1], z[2], c, q) / scale;
      const double d23 = channelDiff(z[2], z[3], c, q) / scale;
      std::printf("dp5 point %d channel %d: relative differences %.3e %.3e %.3e, ratios %.1f %.1f\n",
                  q, c, d01, d12, d23, d01 / d12, d12 / d23);
      EXPECT_LT(d12 * 32.0 / 31.0, 1e-6) << "point " << q << " channel " << c;  // 3 ms error
      EXPECT_NEAR(d12 / d23, 32.0, 8.0) << "point " << q << " channel " << c;
      // Against an independent fine RK4 solution.
      EXPECT_LT(channelDiff(z[1], rk4_fine, c, q) / scale, 1e-6);
    }
  }
}

TEST(RollPlaneDynamics, ZeroRoadKeepsEquilibriumExactly) {
  Eigen::MatrixXd params;
  for (int road_kind = 0; road_kind < 2; ++road_kind) {
    std::shared_ptr<const ContactRoad> road;
    if (road_kind == 0) {
      SineSettings s;
      s.amplitude = 0.0;
      road = std::make_shared<SineRoad>(s);
    } else {
      road = std::make_shared<SampledRoad>(
          std::vector<double>{0.0, 0.5, 1.0, 2.0},
          std::vector<std::vector<double>>(2, std::vector<double>(4, 0.0)));
    }
    const RollPlaneModel model(VehicleParameters(), road);
    params.resize(kRows, 3);
    params.col(0) = paramsAt(model, 0.0, 0.0);
    params.col(1) = paramsAt(model, 1.0, 1.0);  // tilted equilibrium, theta_s != 0
    params.col(2) = paramsAt(model, -0.8, -0.9);
    Eigen::ArrayXXd y;
    const Eigen::MatrixXd z = sampledChannels(model, params, 1e-3, &y);
    for (Eigen::Index i = 0; i < y.size(); ++i) EXPECT_EQ(y(i), 0.0) << "road " << road_kind;
    for (Eigen::Index i = 0; i < z.size(); ++i) EXPECT_EQ(z(i), 0.0) << "road " << road_kind;
  }
}

TEST(RollPlaneDynamics, UnitStepRoadSettlesAtStaticOffset) {
  // A road raised by 1 cm under both tyres from t = 0: after the transient every height is
  // +1 cm and the suspension returns to its static extension (u = 0), for any spring law.
  const RollPlaneModel model(
      VehicleParameters(),
      std::make_shared<SampledRoad>(std::vector<double>{0.0},
                                    std::vector<std::vector<double>>{{0.01}, {0.01}}));
  Eigen::MatrixXd params(kRows, 1);
  params.col(0) = paramsAt(model, 0.6, 0.4);
  const auto batch = model.prepare(params);
  Eigen::ArrayXXd y = batch->initialState();
  integrate(model, *batch, 0.0, 30.0, y, IntegratorSettings());
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(y(i, 0), 0.01, 1e-6) << model.stateNames()[i];
  for (int i = 4; i < 8; ++i) EXPECT_NEAR(y(i, 0), 0.0, 1e-6) << model.stateNames()[i];
}

Eigen::MatrixXd randomColumns(const RollPlaneModel& model, int count) {
  std::mt19937 rng(20080601);
  std::uniform_real_distribution<double> xi(-1.0, 1.0), factor(0.8, 1.2);
  Eigen::MatrixXd params(kRows, count);
  for (int q = 0; q < count; ++q) {
    params.col(q) = paramsAt(model, xi(rng), xi(rng));
    params(3, q) *= factor(rng);  // damping_left
    params(6, q) *= factor(rng);  // spring_linear_right
  }
  return params;
}

TEST(RollPlaneDynamics, BatchEqualsColumnByColumn) {
  const RollPlaneModel model(VehicleParameters(),
                             std::make_shared<SpeedBumpRoad>(SpeedBumpSettings()));
  const Eigen::MatrixXd params = randomColumns(model, 30);
  Eigen::ArrayXXd batch_state;
  const Eigen::MatrixXd batch = sampledChannels(model, params, 1e-3, &batch_state);
  // Not bit for bit: how the compiler vectorises the batch loops and their
  // scalar tails, and where it contracts a*b + c into an FMA, depends on the
  // optimisation level (Release agrees exactly; the sanitizer build differs
  // by 2.9e-15 relative). A wrong column or parameter would be off by >1e-3.
  double worst = 0.0;
  for (int q = 0; q < 30; ++q) {
    Eigen::ArrayXXd single_state;
    const Eigen::MatrixXd single = sampledChannels(model, params.col(q), 1e-3, &single_state);
    const double z_error = (single.col(0) - batch.col(q)).cwiseAbs().maxCoeff() /
                           single.col(0).cwiseAbs().maxCoeff();
    const double y_error = (single_state.col(0) - batch_state.col(q)).abs().maxCoeff() /
                           single_state.col(0).abs().maxCoeff();
    EXPECT_LE(z_error, 1e-12) << "column " << q;
    EXPECT_LE(y_error, 1e-12) << "column " << q;
    worst = std::max({worst, z_error, y_error});
  }
  std::cout << "batch vs column by column: largest relative difference " << worst << std::endl;
}

TEST(RollPlaneDynamics, NonFiniteColumnDoesNotSpread) {
  const RollPlaneModel model(VehicleParameters(),
                             std::make_shared<SpeedBumpRoad>(SpeedBumpSettings()));
  const Eigen::MatrixXd params = randomColumns(model, 4);
  const auto batch = model.prepare(params);
  Eigen::ArrayXXd clean = batch->initialState();
  Eigen::ArrayXXd dirty = clean;
  dirty(5, 2) = std::numeric_limits<double>::quiet_NaN();
  integrate(model, *batch, 0.0, 1.0, clean, IntegratorSettings());
  integrate(model, *batch, 0.0, 1.0, dirty, IntegratorSettings());
  EXPECT_FALSE(dirty.col(2).allFinite());
  for (int q : {0, 1, 3}) EXPECT_TRUE((dirty.col(q) == clean.col(q)).all()) << q;
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
