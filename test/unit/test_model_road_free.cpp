// Roads by distance (ISO 8608, measured profiles) and the road-free roll
// plane (docs/method.md §1.5, §4.10): the rough road's variance against the
// integral of its PSD, and the road-free outputs against the full model's
// readings on the same drive.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "pc_ekf/model/full_car_road_free.h"
#include "pc_ekf/model/input_noise.h"
#include "pc_ekf/model/integrator.h"
#include "pc_ekf/model/model_type.h"
#include "pc_ekf/model/roll_plane_model.h"
#include "pc_ekf/model/roll_plane_road_free.h"
#include "pc_ekf/model/road_profile.h"

namespace pc_ekf {
namespace {

TEST(Iso8608Road, VarianceIsTheIntegralOfThePsd) {
  for (char road_class : {'A', 'C'}) {
    Iso8608Settings s;
    s.road_class = road_class;
    s.lead_in = 0.0;
    const Iso8608Profile road(s);
    // Gd(n) = Gd(n0) (n0 / n)^2 integrated over [n_min, n_max].
    const double g0 = iso8608Roughness(road_class), n0 = 0.1;
    const double expected = g0 * n0 * n0 * (1.0 / s.n_min - 1.0 / s.n_max);
    double sum = 0.0, sum_sq = 0.0, cross = 0.0;
    long count = 0;
    for (double x = 0.01; x < 20000.0; x += 0.37) {
      const double l = road.height(0, x), r = road.height(1, x);
      sum += l;
      sum_sq += l * l;
      cross += l * r;
      ++count;
    }
    const double variance = sum_sq / count - (sum / count) * (sum / count);
    EXPECT_NEAR(variance / expected, 1.0, 0.05) << road_class;
    EXPECT_LT(std::abs(cross / count) / variance, 0.1) << "independent tracks";
  }
  EXPECT_DOUBLE_EQ(iso8608Roughness('B'), 64e-6);
  EXPECT_THROW(iso8608Roughness('F'), std::invalid_argument);
}

TEST(Iso8608Road, CorrelatedTracksSeedsAndLeadIn) {
  Iso8608Settings s;
  s.correlation = 1.0;
  const Iso8608Profile same(s);
  for (double x : {3.0, 17.5, 120.0}) EXPECT_NEAR(same.height(1, x), same.height(0, x), 1e-15);
  Iso8608Settings other = s;
  other.seed = 2;
  EXPECT_NE(Iso8608Profile(other).height(0, 10.0), same.height(0, 10.0));
  EXPECT_EQ(same.height(0, 0.0), 0.0);  // at rest on level ground at s = 0
  EXPECT_LT(std::abs(same.height(0, 0.01)), 1e-5);
}

TEST(MeasuredProfile, InterpolatesByDistanceFromItsFirstSample) {
  const MeasuredProfile p({10.0, 10.5, 11.0}, {0.0, 0.01, -0.01}, {0.0, 0.0, 0.02});
  EXPECT_DOUBLE_EQ(p.length(), 1.0);
  EXPECT_NEAR(p.height(0, 0.25), 0.005, 1e-15);
  EXPECT_NEAR(p.height(1, 0.75), 0.01, 1e-15);
  EXPECT_EQ(p.height(0, 5.0), -0.01);  // held after the end
  EXPECT_EQ(p.kinks(0.0, 1.0), (std::vector<double>{0.5}));
  EXPECT_THROW(MeasuredProfile({0.0, 0.0}, {0.0, 0.0}, {0.0, 0.0}), std::invalid_argument);
}

TEST(DrivenProfileRoad, ContactsLagByDistanceAtTheSpeed) {
  auto p = std::make_shared<MeasuredProfile>(std::vector<double>{0.0, 10.0},
                                             std::vector<double>{0.0, 1.0},
                                             std::vector<double>{0.0, 2.0});
  const DrivenProfileRoad road(p, 10.0, {{0, 0.0}, {1, 0.0}, {0, 2.6}});
  Eigen::VectorXd h(3);
  road.heights(0.5, h);  // 5 m travelled
  EXPECT_NEAR(h[0], 0.5, 1e-15);
  EXPECT_NEAR(h[1], 1.0, 1e-15);
  EXPECT_NEAR(h[2], 0.24, 1e-15);  // 2.4 m on the rear
}

// The full model drives a rough road; its clean suspension readings and gyro
// are the road-free model's inputs. At the true parameters the road-free
// accel_z equals the full model's (to the integrator's and the cos(phi)
// approximation's accuracy), in both conventions.
// The roll plane's channel names are one list: the description's channels,
// the model type's road-free inputs and the road-free model's states read it.
TEST(RollPlaneChannels, OneListForTheDescriptionTheTypeAndTheRoadFreeModel) {
  const std::vector<std::string> names{"u1",      "u2",     "v1",    "v2",    "accel_y",
                                       "accel_z", "gyro_x", "speed", "gyro_z"};
  EXPECT_EQ(pc_ekf::rollPlaneChannels(), names);
  EXPECT_EQ(pc_ekf::rollPlaneDescription().channelNames(), names);
  const auto inputs = pc_ekf::rollPlaneType()->roadFreeInputs();
  EXPECT_EQ(inputs.required, (std::vector<std::string>{"u1", "u2", "v1", "v2"}));
  EXPECT_EQ(inputs.optional, (std::vector<std::string>{"gyro_x", "speed", "gyro_z"}));
}

TEST(RollPlaneRoadFree, ReproducesTheFullModelsImuFromItsSuspensionReadings) {
  for (const ZeroConvention zero : {ZeroConvention::kTare, ZeroConvention::kRest}) {
    VehicleParameters p;
    p.added_mass = 280.0;
    p.added_mass_position = 0.9;
    Iso8608Settings s;
    s.road_class = 'C';
    auto road = std::make_shared<DrivenProfileRoad>(std::make_shared<Iso8608Profile>(s), 10.0,
                                                    std::vector<std::pair<int, double>>{{0, 0.0}, {1, 0.0}});
    const RollPlaneModel full(p, road, {zero, true});
    Eigen::MatrixXd params = p.toVector();
    const auto batch = full.prepare(params);
    Eigen::ArrayXXd y = batch->initialState();
    IntegratorSettings is;
    is.max_step = 2.5e-4;
    std::vector<double> times;
    std::vector<std::vector<double>> in(5);
    std::vector<double> accel_z, accel_y, gyro;
    double t = 0.0;
    for (int k = 1; k <= 400; ++k) {
      const double tk = k * 0.005;
      integrate(full, *batch, t, tk, y, is);
      t = tk;
      times.push_back(tk);
      for (int c = 0; c < 4; ++c) in[c].push_back(y(8 + c, 0));
      in[4].push_back(y(14, 0));
      accel_y.push_back(y(12, 0));
      accel_z.push_back(y(13, 0));
      gyro.push_back(y(14, 0));
    }
    auto inputs = std::make_shared<ReadingInputs>(
        std::vector<std::string>{"u1", "u2", "v1", "v2", "gyro_x"}, times, in);
    const RollPlaneRoadFreeModel free(p, inputs, zero);
    EXPECT_EQ(free.stateSize(), 3);
    EXPECT_TRUE(free.channelIsInput(0));
    EXPECT_TRUE(free.channelModelled(5));
    const auto fb = free.prepare(params);
    double worst_z = 0.0, worst_y = 0.0, worst_gyro = 0.0, motion = 0.0;
    for (std::size_t k = 0; k < times.size(); ++k) {
      Eigen::ArrayXXd r = fb->initialState();
      integrate(free, *fb, 0.0, times[k], r, is);
      worst_z = std::max(worst_z, std::abs(r(1, 0) - accel_z[k]));
      worst_y = std::max(worst_y, std::abs(r(0, 0) - accel_y[k]));
      worst_gyro = std::max(worst_gyro, std::abs(r(2, 0) - gyro[k]));
      motion = std::max(motion, std::abs(accel_z[k] - (zero == ZeroConvention::kTare ? 9.81 : 0.0)));
    }
    EXPECT_GT(motion, 0.5);             // the road shakes the body
    EXPECT_LT(worst_z, 2e-3 * motion);  // cos(phi) of the dynamic roll only
    EXPECT_LT(worst_y, 5e-3);           // the gyro's integral by trapezoids
    EXPECT_LT(worst_gyro, 2e-3);        // the increment's trapezoid over 5 ms
    // A lighter load in the model: accel_z larger by about g dM / (m + M).
    VehicleParameters lighter = p;
    lighter.added_mass = 270.0;
    Eigen::MatrixXd lp = lighter.toVector();
    const auto lb = free.prepare(lp);
    Eigen::ArrayXXd a = lb->initialState(), b = fb->initialState();
    integrate(free, *lb, 0.0, times[200], a, is);
    integrate(free, *fb, 0.0, times[200], b, is);
    if (zero == ZeroConvention::kTare) {
      // (the IMU's lever arm to the combined centre moves too: 10 % of it)
      EXPECT_NEAR(a(1, 0) - b(1, 0), b(1, 0) * 10.0 / (580.0 + 270.0), 0.02);
    }
  }
}

// The same for the full car: its corners' readings and gyros drive the
// road-free body, whose accel_z and gyro increments match the full model's.
TEST(FullCarRoadFree, ReproducesTheFullModelsImuFromItsSuspensionReadings) {
  FullCarParameters p;
  p.added_mass = 250.0;
  p.added_mass_x = 0.9;
  p.added_mass_y = 1.0;
  p.imu_x = 0.3;
  p.imu_y = -0.2;
  Iso8608Settings s;
  s.road_class = 'C';
  const double wb = p.wheelbase();
  auto road = std::make_shared<DrivenProfileRoad>(
      std::make_shared<Iso8608Profile>(s), 10.0,
      std::vector<std::pair<int, double>>{{0, 0.0}, {1, 0.0}, {0, wb}, {1, wb}});
  const FullCarModel full(p, road, {ZeroConvention::kTare, true});
  Eigen::MatrixXd params = p.toVector();
  const auto batch = full.prepare(params);
  Eigen::ArrayXXd y = batch->initialState();
  IntegratorSettings is;
  is.max_step = 2.5e-4;
  std::vector<double> times;
  std::vector<std::vector<double>> in(10);
  std::vector<Eigen::Vector4d> imu;
  double t = 0.0;
  for (int k = 1; k <= 300; ++k) {
    const double tk = k * 0.005;
    integrate(full, *batch, t, tk, y, is);
    t = tk;
    times.push_back(tk);
    for (int c = 0; c < 8; ++c) in[c].push_back(y(14 + c, 0));
    in[8].push_back(y(24, 0));
    in[9].push_back(y(25, 0));
    imu.emplace_back(y(22, 0), y(23, 0), y(24, 0), y(25, 0));
  }
  auto inputs = std::make_shared<ReadingInputs>(
      std::vector<std::string>{"u_fl", "u_fr", "u_rl", "u_rr", "v_fl", "v_fr", "v_rl", "v_rr",
                               "gyro_x", "gyro_y"},
      times, in);
  const FullCarRoadFreeModel free(p, inputs, ZeroConvention::kTare);
  EXPECT_EQ(free.stateSize(), 4);
  EXPECT_TRUE(free.channelIsInput(7));
  EXPECT_TRUE(free.channelModelled(11));
  const auto fb = free.prepare(params);
  double worst[4] = {0, 0, 0, 0}, motion = 0.0;
  for (std::size_t k = 0; k < times.size(); ++k) {
    Eigen::ArrayXXd r = fb->initialState();
    integrate(free, *fb, 0.0, times[k], r, is);
    for (int c = 0; c < 4; ++c) worst[c] = std::max(worst[c], std::abs(r(c, 0) - imu[k][c]));
    motion = std::max(motion, std::abs(imu[k][1] - 9.81));
  }
  EXPECT_GT(motion, 0.3);
  // What is left is the gyros' integrals and increments by trapezoids over
  // 5 ms (measured: 6.6e-5, 1.1e-6, 2.0e-4, 9.6e-5). A pitch of the wrong
  // sign in the attitude (pitch_static + theta for pitch_static - theta)
  // left 3e-3 m/s^2 on accel_z, correlated with the pitch: M biased.
  EXPECT_LT(worst[1], 1e-5);  // accel_z: the attitude's integrals, to second order
  EXPECT_LT(worst[0], 2e-4);  // accel_y: the gyros' integrals
  EXPECT_LT(worst[2], 5e-4);  // gyro increments
  EXPECT_LT(worst[3], 5e-4);
}

// A stream (the node) appends the samples one by one: the same inputs,
// integrals and previous times as the whole record, and a missing reading
// held at its last value; a refused sample changes nothing.
TEST(ReadingInputs, AStreamIsTheWholeRecord) {
  std::vector<double> times;
  std::vector<std::vector<double>> in(2);
  for (int k = 1; k <= 40; ++k) {
    times.push_back(0.005 * k + 0.001 * (k % 3));
    in[0].push_back(std::sin(0.3 * k));
    in[1].push_back(0.1 * k * k);
  }
  const std::vector<std::string> names{"u1", "gyro_x"};
  const ReadingInputs whole(names, times, in);
  ReadingInputs stream(names);
  EXPECT_TRUE(stream.empty());
  for (std::size_t k = 0; k < times.size(); ++k) {
    const double row[2] = {in[0][k], in[1][k]};
    ASSERT_EQ(stream.append(times[k], row), "");
  }
  for (double t : {0.0, 0.0031, 0.05, 0.1234, 0.2, 0.25}) {
    double a[2], b[2];
    whole.at(t, a);
    stream.at(t, b);
    EXPECT_EQ(a[0], b[0]);
    EXPECT_EQ(a[1], b[1]);
    EXPECT_DOUBLE_EQ(whole.integral(1, t), stream.integral(1, t));
    EXPECT_EQ(whole.previousTime(t), stream.previousTime(t));
  }
  const double nan = std::nan("");
  const double late[2] = {nan, 5.0};
  EXPECT_NE(stream.append(times.back(), late).find("not after the last"), std::string::npos);
  ASSERT_EQ(stream.append(1.0, late), "");
  double held[2];
  stream.at(1.0, held);
  EXPECT_EQ(held[0], in[0].back());  // u1 held
  EXPECT_EQ(held[1], 5.0);
  ReadingInputs fresh(names);
  EXPECT_NE(fresh.append(0.1, late).find("'u1' not read yet"), std::string::npos);
  EXPECT_TRUE(fresh.empty());
  const double inf[2] = {1.0, INFINITY};
  EXPECT_NE(fresh.append(0.1, inf).find("'gyro_x' not finite"), std::string::npos);
  EXPECT_TRUE(fresh.empty());
}

// A stream that forgets what no reader needs (the node over hours, and
// estimate_offline's road-free one-step) holds a bounded tail and the
// record's first samples that a batch reads, and reads there exactly as the
// whole record does; its integrals and sample sums run on over the
// forgotten samples; a read that would need a forgotten sample throws.
TEST(ReadingInputs, AForgettingStreamReadsAsTheWholeRecord) {
  const int n = 20000;
  std::vector<double> times;
  std::vector<std::vector<double>> in(2);
  for (int k = 1; k <= n; ++k) {
    times.push_back(0.005 * k + 0.001 * (k % 3));
    in[0].push_back(std::sin(0.01 * k) - 0.5 * (k % 7 == 0));
    in[1].push_back(0.02 * std::cos(0.003 * k));
  }
  const std::vector<std::string> names{"u1", "gyro_x"};
  const ReadingInputs whole(names, times, in);
  ReadingInputs stream(names);
  const auto force = [](const double* x) { return 3.0 * x[0] + x[0] * x[0] * x[0] - x[1]; };
  const int sum = stream.addSampleSum(force);
  const double batch_end = times[99];  // a batch over the first 100 samples
  const double window = 0.5;          // s: what the filters still read
  std::size_t most = 0;
  for (int k = 0; k < n; ++k) {
    const double row[2] = {in[0][k], in[1][k]};
    ASSERT_EQ(stream.append(times[k], row), "");
    stream.forget(times[k] - window, batch_end);
    most = std::max(most, stream.held());
  }
  EXPECT_EQ(stream.samples(), static_cast<std::size_t>(n));
  // 100 first samples, a window of ~100, forgotten in chunks of 4096.
  EXPECT_LT(most, 100u + 2u * 4096u + 300u);
  EXPECT_LT(stream.held(), static_cast<std::size_t>(n) / 2);
  const double kept_from = times[n - 1] - window;
  std::vector<double> probes{0.0, 0.002, times[0], 0.5 * (times[40] + times[41]), times[99]};
  for (int k = n - 90; k < n; k += 7) {
    probes.push_back(times[k]);
    probes.push_back(times[k] + 0.001);
  }
  probes.push_back(times[n - 1] + 0.3);
  for (double t : probes) {
    SCOPED_TRACE(t);
    double a[2], b[2];
    whole.at(t, a);
    stream.at(t, b);
    EXPECT_EQ(a[0], b[0]);
    EXPECT_EQ(a[1], b[1]);
    EXPECT_EQ(whole.integral(1, t), stream.integral(1, t));
    if (t > kept_from || t <= times[99]) {
      EXPECT_EQ(whole.previousTime(t), stream.previousTime(t));
    }
  }
  EXPECT_EQ(stream.time(n - 1), times[n - 1]);
  EXPECT_EQ(stream.time(50), times[50]);
  // Between the batch's samples and the tail: forgotten.
  const double gap = times[n / 2];
  double out[2];
  EXPECT_THROW(stream.at(gap, out), std::logic_error);
  EXPECT_THROW(stream.integral(1, gap), std::logic_error);
  EXPECT_THROW(stream.previousTime(gap), std::logic_error);
  EXPECT_THROW(stream.time(n / 2), std::out_of_range);
  EXPECT_THROW(stream.addSampleSum(force), std::logic_error);
  // The sum over every sample, in order: as the whole record's.
  EXPECT_EQ(stream.sampleSum(sum), whole.sampleSum(whole.addSampleSum(force)));

  // Nothing kept at the start: the front itself is forgotten.
  ReadingInputs tail(names);
  for (int k = 0; k < n; ++k) {
    const double row[2] = {in[0][k], in[1][k]};
    ASSERT_EQ(tail.append(times[k], row), "");
    tail.forget(times[k], -INFINITY);
  }
  EXPECT_LT(tail.held(), 2u * 4096u + 2u);
  EXPECT_THROW(tail.at(times[0], out), std::logic_error);
  EXPECT_EQ(tail.integral(1, times[n - 1]), whole.integral(1, times[n - 1]));
  EXPECT_EQ(tail.previousTime(times[n - 1]), times[n - 2]);
}

// Errors in variables: the variance an output inherits from noisy inputs,
// against Monte Carlo draws of that noise.
TEST(RollPlaneRoadFree, InputNoiseVarianceMatchesMonteCarlo) {
  VehicleParameters p;
  std::vector<double> times;
  std::vector<std::vector<double>> in(4);
  for (int k = 1; k <= 50; ++k) {
    times.push_back(0.01 * k);
    in[0].push_back(-0.03 + 0.01 * std::sin(0.3 * k));
    in[1].push_back(-0.035 + 0.01 * std::cos(0.2 * k));
    in[2].push_back(0.05 * std::sin(0.5 * k));
    in[3].push_back(0.04 * std::cos(0.4 * k));
  }
  const Eigen::Vector4d absolute(5e-4, 5e-4, 5e-3, 5e-3), relative(0.01, 0.01, 0.0, 0.0);
  const auto clean = std::make_shared<ReadingInputs>(
      std::vector<std::string>{"u1", "u2", "v1", "v2"}, times, in);
  const RollPlaneRoadFreeModel model(p, clean, ZeroConvention::kTare);
  const double predicted = model.inputNoiseVariance(absolute, relative, 0.0)[5];
  Eigen::MatrixXd params = p.toVector();
  std::mt19937_64 rng(3);
  std::normal_distribution<double> normal;
  double sum_sq = 0.0;
  long count = 0;
  const auto exact = model.prepare(params);
  for (int draw = 0; draw < 400; ++draw) {
    std::vector<std::vector<double>> noisy = in;
    for (int c = 0; c < 4; ++c) {
      for (double& v : noisy[static_cast<std::size_t>(c)]) v += std::hypot(absolute[c], relative[c] * v) * normal(rng);
    }
    const RollPlaneRoadFreeModel m(p, std::make_shared<ReadingInputs>(clean->names(), times, noisy),
                                   ZeroConvention::kTare);
    const auto b = m.prepare(params);
    for (std::size_t k = 0; k < times.size(); k += 7) {
      Eigen::ArrayXXd r = b->initialState(), e = exact->initialState();
      IntegratorSettings is;
      integrate(m, *b, 0.0, times[k], r, is);
      integrate(model, *exact, 0.0, times[k], e, is);
      sum_sq += (r(1, 0) - e(1, 0)) * (r(1, 0) - e(1, 0));
      ++count;
    }
  }
  EXPECT_NEAR(sum_sq / count / predicted, 1.0, 0.1);
  EXPECT_GT(predicted, 1e-4);  // comparable to a MEMS accelerometer's own noise
}

// Errors in variables with correlated input noise: an output read from an
// input at k and at k - 1, y = 2 x_k + 3 x_(k-1), inherits
// sigma^2 (4 + 9 + 2 rho 6) when the input's noise is correlated rho between
// consecutive samples (a blended travel), sigma^2 (4 + 9) when it is white.
TEST(InputNoise, CorrelatedNoiseBetweenConsecutiveSamples) {
  auto inputs = std::make_shared<ReadingInputs>(std::vector<std::string>{"x"},
                                                 std::vector<double>{0.1, 0.2, 0.3},
                                                 std::vector<std::vector<double>>{{1.0, 2.0, 3.0}});
  const ReadingOutputs linear = [](const double* now, const double* before, bool, double,
                                   const double*, double* out) {
    out[0] = 2.0 * now[0] + 3.0 * before[0];
  };
  const Eigen::VectorXd absolute = Eigen::VectorXd::Constant(1, 0.5), relative = Eigen::VectorXd::Zero(1);
  EXPECT_NEAR(inputOutputCovarianceAt(*inputs, 1, absolute, relative, {}, 1, linear)(0, 0),
              0.25 * 13.0, 1e-12);
  inputs->setNoiseCorrelation(0, 0.8);
  EXPECT_NEAR(inputOutputCovarianceAt(*inputs, 1, absolute, relative, {}, 1, linear)(0, 0),
              0.25 * (13.0 + 2.0 * 0.8 * 6.0), 1e-12);
  // The first sample has nothing before it.
  EXPECT_NEAR(inputOutputCovarianceAt(*inputs, 0, absolute, relative, {}, 1, linear)(0, 0),
              0.25 * 4.0, 1e-12);
  EXPECT_THROW(inputs->setNoiseCorrelation(0, 1.0), std::invalid_argument);
}

// Two outputs of the same two inputs: their errors are correlated, by the
// closed form J S J' (J the outputs' derivatives by the inputs' noise, S the
// noise's covariance, consecutive samples of input 0 correlated by rho).
TEST(InputNoise, OutputsOfTheSameInputsAreCorrelated) {
  auto inputs = std::make_shared<ReadingInputs>(
      std::vector<std::string>{"x", "y"}, std::vector<double>{0.1, 0.2},
      std::vector<std::vector<double>>{{1.0, 2.0}, {-1.0, 0.5}});
  const ReadingOutputs linear = [](const double* now, const double* before, bool, double,
                                   const double*, double* out) {
    out[0] = 2.0 * now[0] - now[1] + 3.0 * before[0];
    out[1] = 4.0 * now[0] + 0.5 * before[1];
  };
  const Eigen::Vector2d absolute(0.5, 0.2), relative = Eigen::Vector2d::Zero();
  inputs->setNoiseCorrelation(0, 0.6);
  // Noise sources: x now, y now, x before, y before.
  Eigen::Matrix<double, 2, 4> j;
  j << 2.0, -1.0, 3.0, 0.0,
       4.0, 0.0, 0.0, 0.5;
  Eigen::Matrix4d s = Eigen::Vector4d(0.25, 0.04, 0.25, 0.04).asDiagonal();
  s(0, 2) = s(2, 0) = 0.6 * 0.25;
  const Eigen::Matrix2d expected = j * s * j.transpose();
  const Eigen::MatrixXd got = inputOutputCovarianceAt(*inputs, 1, absolute, relative, {}, 2, linear);
  ASSERT_EQ(got.rows(), 2);
  ASSERT_EQ(got.cols(), 2);
  EXPECT_LT((got - expected).cwiseAbs().maxCoeff(), 1e-12) << got << "\nexpected\n" << expected;
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
