// Road-free full car (full_car_road_free.h, docs/method.md §4.10).
#include "pc_ekf/model/full_car_road_free.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "pc_ekf/model/input_noise.h"
#include "pc_ekf/model/instant_part.h"
#include "pc_ekf/model/smooth_functions.h"

namespace pc_ekf {

struct FullCarRoadFreeConstants {
  struct Point {
    double x[4], y[4], k[4], k3[4], damping[4], delta_ref[4];
    Eigen::Matrix3d inv_mass;
    Eigen::Vector3d weight;  // (m_s + M) g, M x_M g, M y_M g
    double imu_x, imu_y, roll_static, pitch_static, gravity, rest_y, rest_z;
    double rest_x;  // accel_x at rest: g theta_s (rest); 0 (tare)
    // Heights and bars (docs/models.md): M_b with the heights, k_a per axle,
    // S = m_s h_b + M h_M, S g tan(theta_s), S g tan(phi_s), z_I.
    Eigen::Matrix3d mass;
    double bar[2], first_moment, static_pitch, static_roll, imu_height;
    // atan(slope) - slope of the static pitch and roll: the S terms' angles
    // are the model on a road's (theta_s = atan(tan(theta_s))).
    double pitch_offset, roll_offset;
  };
  std::vector<Point> points;
  DamperLaw law = DamperLaw::kTanh;
  double tanh_rate = 0.0;
  // Where the optional inputs are (-1: not read): the gyros (x, y), speed and
  // yaw rate (a_y = speed x yaw rate), accel_x (a_x).
  int gyro_x = -1, gyro_y = -1, speed = -1, yaw = -1, accel_x = -1;
  // Some point has heights, bars or an IMU height, or a_x or a_y is read: the
  // general outputs (else today's, bit for bit).
  bool elevated = false;
};

namespace {

constexpr int kMaxInputs = 13;  // u_fl .. v_rr [gyro_x gyro_y] [speed gyro_z] [accel_x]

// The body's angles at an instant: theta (front up) and phi (left up),
// totals (static plus the gyros' integrals since rest).
struct Attitude {
  double theta, phi;
};

// The horizontal accelerations from the inputs `now`: a_y = speed x gyro_z;
// a_x from the raw accel_x (the reading plus the rest convention's
// g theta_s) less the tilt's g theta (outputs() refines it with the body's
// accelerations); 0 for what is not read. Not the speed's difference: at
// 200 Hz a wheel-speed noise of 0.05 m/s makes it 14 m/s^2 of noise.
void horizontal(const FullCarRoadFreeConstants& c, const FullCarRoadFreeConstants::Point& p,
                const double* now, double theta, double* a_x, double* a_y) {
  *a_y = c.speed < 0 ? 0.0 : now[c.speed] * now[c.yaw];
  *a_x = c.accel_x < 0 ? 0.0 : now[c.accel_x] + p.rest_x - p.gravity * theta;
}

// (z'', theta'', phi'') for inputs `in`; *specific = g + a at the IMU.
// With heights, bars or a horizontal motion (docs/models.md): the bars'
// force k_a (x_l - x_r) on each axle's left end (x the compressions), minus
// it on the right, and
//   M_b q'' = sum F_i [1, x_i, y_i] - [(m_s + M) g, M x_M g, M y_M g]
//             + [0, S (a_x cos(theta) + (g + z'') sin(theta)) + (1 - cos(theta)) S g tan(theta_s),
//                   S (a_y cos(phi) + (g + z'') sin(phi)) + (1 - cos(phi)) S g tan(phi_s)]
// with the total forces F_i (their static part carries -S g tan(theta_s)
// and -S g tan(phi_s): the model on a road's equations, in total forces).
Eigen::Vector3d bodyAcceleration(const FullCarRoadFreeConstants& c,
                                 const FullCarRoadFreeConstants::Point& p, const double* in,
                                 const Attitude& angle, double a_x, double a_y,
                                 double* specific) {
  Eigen::Vector3d load = -p.weight;
  double x[4], f[4];
  for (int i = 0; i < 4; ++i) {
    x[i] = p.delta_ref[i] - in[i];
    const double v = in[4 + i];
    const double damper = c.law == DamperLaw::kTanh
                              ? damperForce<DamperLaw::kTanh>(p.damping[i], c.tanh_rate, v)
                              : damperForce<DamperLaw::kLinear>(p.damping[i], c.tanh_rate, v);
    f[i] = p.k[i] * x[i] + p.k3[i] * x[i] * x[i] * x[i] - damper;
  }
  if (!c.elevated) {
    for (int i = 0; i < 4; ++i) load += f[i] * Eigen::Vector3d(1.0, p.x[i], p.y[i]);
    const Eigen::Vector3d q = p.inv_mass * load;
    *specific = p.gravity + q[0] + p.imu_x * q[1] + p.imu_y * q[2];
    return q;
  }
  for (int axle = 0; axle < 2; ++axle) {
    const int left = 2 * axle, right = left + 1;
    const double twist = p.bar[axle] * (x[left] - x[right]);
    f[left] += twist;
    f[right] -= twist;
  }
  for (int i = 0; i < 4; ++i) load += f[i] * Eigen::Vector3d(1.0, p.x[i], p.y[i]);
  const double S = p.first_moment;
  const double theta = angle.theta + p.pitch_offset, phi = angle.phi + p.roll_offset;
  const double cos_theta = std::cos(theta), sin_theta = std::sin(theta);
  const double cos_phi = std::cos(phi), sin_phi = std::sin(phi);
  load[1] += S * (a_x * cos_theta + p.gravity * sin_theta) + (1.0 - cos_theta) * p.static_pitch;
  load[2] += S * (a_y * cos_phi + p.gravity * sin_phi) + (1.0 - cos_phi) * p.static_roll;
  Eigen::Matrix3d mass = p.mass;
  mass(1, 0) -= S * sin_theta;
  mass(2, 0) -= S * sin_phi;
  const Eigen::Vector3d q = mass.inverse() * load;
  *specific = p.gravity + q[0] + p.imu_x * q[1] + p.imu_y * q[2];
  return q;
}

// The outputs accel_y, accel_z, gyro_x, gyro_y of one point. angle_now and
// angle_before: the gyros' integrals since rest (roll; REP 103 pitch, nose
// down > 0) at t and at the sample before; gyro_before: the gyros' readings
// there (x, y).
// The body's accelerations at one instant, with what outputs() reads of
// them; kept by the input slopes (instant_part.h). The instant before keeps a.
struct BodyPart {
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  double specific = 0.0, a_x = 0.0, a_y = 0.0;
};
using BodyParts = OutputParts<kMaxInputs, 2, BodyPart>;

void outputs(const FullCarRoadFreeConstants& c, const FullCarRoadFreeConstants::Point& p,
             const double* now, const double* before, bool before_at_rest, double dt,
             double roll, double pitch, double roll_before, double pitch_before,
             const double* gyro_before, double* out, BodyParts* parts = nullptr) {
  const double r = p.roll_static + roll, pt = p.pitch_static + pitch;
  const Attitude angle{-pt, r};
  double a_x = 0.0, a_y = 0.0, specific = 0.0, unused = 0.0;
  Eigen::Vector3d a;
  const double angles_now[2] = {roll, pitch};
  if (parts && parts->now.same(now, parts->count, angles_now)) {
    a = parts->now.part.a;
    specific = parts->now.part.specific;
    a_x = parts->now.part.a_x;
    a_y = parts->now.part.a_y;
  } else {
    if (c.elevated) horizontal(c, p, now, angle.theta, &a_x, &a_y);
    a = bodyAcceleration(c, p, now, angle, a_x, a_y, &specific);
    if (c.accel_x >= 0) {
      // accel_x = a_x + (g + z'') theta - z_I theta'' - imu_x theta'^2: once
      // more with this solution's z'' and theta'' (theta' the gyro's).
      const double pitch_rate = c.gyro_y < 0 ? 0.0 : now[c.gyro_y];
      a_x += -a[0] * angle.theta + p.imu_height * a[1] + p.imu_x * pitch_rate * pitch_rate;
      a = bodyAcceleration(c, p, now, angle, a_x, a_y, &specific);
    }
    if (parts) parts->now.keep(now, parts->count, angles_now, BodyPart{a, specific, a_x, a_y});
  }
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  if (!before_at_rest) {
    const double angles_before[2] = {roll_before, pitch_before};
    if (parts && parts->before.same(before, parts->count, angles_before)) {
      b = parts->before.part.a;
    } else {
      const Attitude angle_before{-(p.pitch_static + pitch_before), p.roll_static + roll_before};
      double bx = 0.0, by = 0.0;
      // The sample before's a_x: accel_x's then (to first order).
      if (c.elevated) horizontal(c, p, before, angle_before.theta, &bx, &by);
      b = bodyAcceleration(c, p, before, angle_before, bx, by, &unused);
      if (parts) parts->before.keep(before, parts->count, angles_before, BodyPart{b, 0.0, 0.0, 0.0});
    }
  }
  out[2] = (before_at_rest ? 0.0 : gyro_before[0]) + 0.5 * (a[2] + b[2]) * dt;
  out[3] = (before_at_rest ? 0.0 : gyro_before[1]) - 0.5 * (a[1] + b[1]) * dt;
  if (c.elevated) {
    // a_y, a_x and the IMU's height z_I (the rates the gyros read, when they are).
    const double roll_rate = c.gyro_x < 0 ? 0.0 : now[c.gyro_x];
    const double pitch_rate = c.gyro_y < 0 ? 0.0 : now[c.gyro_y];
    const double level = specific * std::cos(pt);
    out[0] = level * std::sin(r) + a_y * std::cos(r) - p.imu_height * a[2] - p.rest_y;
    out[1] = level * std::cos(r) - a_y * r - a_x * angle.theta -
             p.imu_height * (roll_rate * roll_rate + pitch_rate * pitch_rate) - p.rest_z;
    return;
  }
  out[0] = specific * std::cos(pt) * std::sin(r) - p.rest_y;
  out[1] = specific * std::cos(pt) * std::cos(r) - p.rest_z;
}

class FullCarRoadFreeBatch : public ModelBatch {
 public:
  FullCarRoadFreeBatch(std::unique_ptr<FullCarRoadFreeConstants> c,
                       std::shared_ptr<const ReadingInputs> in)
      : c_(std::move(c)), in_(std::move(in)) {}
  int pointCount() const override { return static_cast<int>(c_->points.size()); }
  void derivatives(double, const Eigen::ArrayXXd& y, Eigen::ArrayXXd& dydt) const override {
    dydt.resize(y.rows(), y.cols());  // no dynamic state
  }
  Eigen::ArrayXXd initialState() const override {
    Eigen::ArrayXXd y = Eigen::ArrayXXd::Zero(4, pointCount());
    for (Eigen::Index q = 0; q < y.cols(); ++q) {
      const auto& p = c_->points[static_cast<std::size_t>(q)];
      const double level = p.gravity * std::cos(p.pitch_static);
      y(0, q) = level * std::sin(p.roll_static) - p.rest_y;
      y(1, q) = level * std::cos(p.roll_static) - p.rest_z;
    }
    return y;
  }
  void readings(double t, Eigen::ArrayXXd& y) const override {
    const int gx = c_->gyro_x, gy = c_->gyro_y;
    const bool gyros = gx >= 0;
    double now[kMaxInputs] = {}, before[kMaxInputs] = {};
    in_->at(t, now);
    const double t_before = in_->previousTime(t);
    const bool at_rest = !(t_before > 0.0);
    if (!at_rest) in_->at(t_before, before);
    const double roll = gyros ? in_->integral(gx, t) : 0.0;
    // REP 103 pitch since rest (nose down > 0): gyro_y's integral, as the
    // full model's pitch_static - theta.
    const double pitch = gyros ? in_->integral(gy, t) : 0.0;
    const bool before_angles = gyros && !at_rest && c_->elevated;
    const double roll_before = before_angles ? in_->integral(gx, t_before) : 0.0;
    const double pitch_before = before_angles ? in_->integral(gy, t_before) : 0.0;
    const double gyro_before[2] = {gyros ? before[gx] : 0.0, gyros ? before[gy] : 0.0};
    double out[4];
    for (Eigen::Index q = 0; q < y.cols(); ++q) {
      outputs(*c_, c_->points[static_cast<std::size_t>(q)], now, before, at_rest, t - t_before,
              roll, pitch, roll_before, pitch_before, gyro_before, out);
      for (int r = 0; r < 4; ++r) y(r, q) = out[r];
    }
  }

 private:
  std::unique_ptr<FullCarRoadFreeConstants> c_;
  std::shared_ptr<const ReadingInputs> in_;
};

// A road that is never driven: the wrapped model is used for its checks only.
class NoRoad : public ContactRoad {
 public:
  int contactCount() const override { return 4; }
  void heights(double, Eigen::Ref<Eigen::VectorXd> out) const override { out.setZero(); }
  std::vector<double> breakpoints(double, double) const override { return {}; }
};

}  // namespace

FullCarRoadFreeModel::FullCarRoadFreeModel(const FullCarParameters& nominal,
                                           std::shared_ptr<const ReadingInputs> inputs,
                                           ZeroConvention zero)
    : nominal_(nominal),
      with_road_(nominal, std::make_shared<NoRoad>()),
      inputs_(std::move(inputs)),
      zero_(zero),
      nominal_vector_(nominal.toVector()),
      state_names_{"reading_accel_y", "reading_accel_z", "reading_gyro_x", "reading_gyro_y"},
      h_(Eigen::MatrixXd::Zero(FullCarModel::kChannels, 4)) {
  if (!inputs_) throw std::invalid_argument("road-free full car: no inputs");
  // u_fl .. v_rr, then gyro_x gyro_y, speed gyro_z and accel_x when read
  // (the gyros together, speed with gyro_z).
  const std::vector<std::string>& names = inputs_->names();
  const auto position = [&](const std::string& name) {
    const auto it = std::find(names.begin(), names.end(), name);
    return it == names.end() ? -1 : static_cast<int>(it - names.begin());
  };
  gyro_x_ = position("gyro_x");
  gyro_y_ = position("gyro_y");
  speed_ = position("speed");
  yaw_ = position("gyro_z");
  accel_x_ = position("accel_x");
  std::vector<std::string> expected{"u_fl", "u_fr", "u_rl", "u_rr",
                                    "v_fl", "v_fr", "v_rl", "v_rr"};
  if (gyro_x_ >= 0 || gyro_y_ >= 0) {
    expected.push_back("gyro_x");
    expected.push_back("gyro_y");
  }
  if (speed_ >= 0 || yaw_ >= 0) {
    expected.push_back("speed");
    expected.push_back("gyro_z");
  }
  if (accel_x_ >= 0) expected.push_back("accel_x");
  if (names != expected) {
    throw std::invalid_argument(
        "road-free full car: inputs must be u_fl .. u_rr, v_fl .. v_rr [gyro_x gyro_y] "
        "[speed gyro_z] [accel_x]");
  }
  h_.middleRows(8, 4).setIdentity();  // accel_y accel_z gyro_x gyro_y
  // With tare the record weighs the load (inputNoiseBySample): the springs'
  // force at the nominal vehicle, summed over the samples as they come.
  if (zero_ == ZeroConvention::kTare) {
    const auto p0 = constants(Eigen::MatrixXd(nominal_vector_))->points.front();
    spring_force_sum_ = inputs_->addSampleSum([p0](const double* in) {
      double f = 0.0;
      for (int i = 0; i < 4; ++i) {
        const double x = p0.delta_ref[i] - in[i];
        f += p0.k[i] * x + p0.k3[i] * x * x * x;
      }
      return f;
    });
  }
}

FullCarRoadFreeModel::~FullCarRoadFreeModel() = default;

bool FullCarRoadFreeModel::channelModelled(int channel) const {
  if (channel == 9) return true;  // accel_z
  return channel >= 8 && channel <= 11 && gyro_x_ >= 0;
}

bool FullCarRoadFreeModel::channelIsInput(int channel) const {
  return channel < 8 || (accel_x_ >= 0 && channel == kAccelXChannel) ||
         (speed_ >= 0 && (channel == kSpeedChannel || channel == kYawChannel));
}

std::unique_ptr<FullCarRoadFreeConstants> FullCarRoadFreeModel::constants(
    const Eigen::MatrixXd& params) const {
  auto c = std::make_unique<FullCarRoadFreeConstants>();
  c->law = nominal_.damper;
  c->tanh_rate = nominal_.damper_tanh_rate;
  const double scale = nominal_.damper == DamperLaw::kTanh ? nominal_.damper_tanh_scale : 1.0;
  const bool tare = zero_ == ZeroConvention::kTare;
  c->gyro_x = gyro_x_;
  c->gyro_y = gyro_y_;
  c->speed = speed_;
  c->yaw = yaw_;
  c->accel_x = accel_x_;
  c->elevated = speed_ >= 0 || accel_x_ >= 0;
  for (Eigen::Index q = 0; q < params.cols(); ++q) {
    const std::string why = invalidReason(params.col(q));
    if (!why.empty()) {
      throw std::invalid_argument("road-free full car: column " + std::to_string(q) + ": " + why);
    }
    const FullCarColumn p(&params(0, q));
    const FullCarFields<int>& at = p.at();
    // Memoised (invalidReason above solved this point already).
    const FullCarEquilibrium e = with_road_.equilibrium(params.col(q));
    FullCarEquilibrium e0;
    if (tare) {
      Eigen::VectorXd empty = params.col(q);
      empty[at.added_mass] = 0.0;
      e0 = with_road_.equilibrium(empty);
    }
    FullCarRoadFreeConstants::Point a{};
    for (int i = 0; i < 4; ++i) {
      const int axle = FullCarParameters::axle(i);
      a.x[i] = p.cornerX(i);
      a.y[i] = p.cornerY(i);
      a.k[i] = p[at.spring_linear[axle]];
      a.k3[i] = p[at.spring_cubic[axle]];
      a.damping[i] = p[at.damping[axle]] * scale;
      a.delta_ref[i] = tare ? e0.spring_compression[i] : e.spring_compression[i];
    }
    const double m = p[at.added_mass], xm = p.addedMassX(), ym = p.addedMassY(),
                 g = p[at.gravity];
    a.mass = p.bodyMass();
    a.inv_mass = a.mass.inverse();
    a.bar[0] = p[at.anti_roll_bar[0]];
    a.bar[1] = p[at.anti_roll_bar[1]];
    a.first_moment = p[at.body_mass] * p[at.body_cg_height] + m * p[at.added_mass_height];
    a.static_pitch = a.first_moment * g * e.pitch;  // tan(theta_s): the corner plane's slope
    a.static_roll = a.first_moment * g * e.roll;
    a.imu_height = p[at.imu_height];
    a.pitch_offset = std::atan(e.pitch) - e.pitch;
    a.roll_offset = std::atan(e.roll) - e.roll;
    if (a.first_moment != 0.0 || a.bar[0] != 0.0 || a.bar[1] != 0.0 || a.imu_height != 0.0 ||
        p[at.body_cg_height] != 0.0 || p[at.added_mass_height] != 0.0) {
      c->elevated = true;
    }
    a.weight = Eigen::Vector3d((p[at.body_mass] + m) * g, m * xm * g, m * ym * g);
    a.imu_x = p[at.imu_x];
    a.imu_y = p[at.imu_y];
    a.roll_static = e.roll;
    a.pitch_static = -e.pitch;
    a.gravity = g;
    const double level = g * std::cos(a.pitch_static);
    a.rest_y = tare ? 0.0 : level * std::sin(a.roll_static);
    a.rest_z = tare ? 0.0 : level * std::cos(a.roll_static);
    a.rest_x = tare ? 0.0 : g * e.pitch;
    c->points.push_back(a);
  }
  return c;
}

std::unique_ptr<ModelBatch> FullCarRoadFreeModel::prepare(const Eigen::MatrixXd& params) const {
  if (params.rows() != nominal_vector_.size()) {
    throw std::invalid_argument("road-free full car: expected " +
                                std::to_string(nominal_vector_.size()) + " parameter rows");
  }
  return std::make_unique<FullCarRoadFreeBatch>(constants(params), inputs_);
}

MechanicalModel::SampleInputNoise FullCarRoadFreeModel::inputNoiseBySample(const Eigen::VectorXd& absolute,
                                                         const Eigen::VectorXd& relative,
                                                         double mean_accel_z) const {
  const int n = inputs_->count();
  if (absolute.size() != n || relative.size() != n) {
    throw std::invalid_argument("inputNoiseBySample: one std per input");
  }
  Eigen::VectorXd vehicle = nominal_vector_;
  if (zero_ == ZeroConvention::kTare) {  // the load the record weighs
    const int body = fullCarDescription().parameters().at("body_mass");
    const int added = fullCarDescription().parameters().at("added_mass");
    vehicle[added] = weighedLoad(*inputs_, spring_force_sum_, mean_accel_z, vehicle[body],
                                 4.0 * std::max(vehicle[added], vehicle[body]), vehicle[added]);
  }
  std::shared_ptr<const FullCarRoadFreeConstants> c = constants(Eigen::MatrixXd(vehicle));
  const bool gyros = gyro_x_ >= 0;
  const int gx = gyro_x_, gy = gyro_y_;
  const std::vector<int> integrated = gyros ? std::vector<int>{gx, gy} : std::vector<int>{};
  return [c, integrated, absolute, relative, gyros, gx, gy, inputs = inputs_](std::size_t k,
                                                                               Eigen::MatrixXd* slopes) {
    const auto& p = c->points.front();
    Eigen::MatrixXd four;
    BodyParts parts;
    parts.count = std::min(inputs->count(), kMaxInputs);
    const Eigen::MatrixXd v = inputOutputCovarianceAt(
        *inputs, k, absolute, relative, integrated, 4,
        [&](const double* now, const double* before, bool at_rest, double dt, const double* angle,
            double* out) {
          const double gyro_before[2] = {gyros ? before[gx] : 0.0, gyros ? before[gy] : 0.0};
          const double roll = gyros ? angle[0] : 0.0, pitch = gyros ? -angle[1] : 0.0;
          outputs(*c, p, now, before, at_rest, dt, roll, pitch, roll, pitch, gyro_before, out,
                  &parts);
        },
        slopes ? &four : nullptr);
    Eigen::MatrixXd covariance =
        Eigen::MatrixXd::Zero(FullCarModel::kChannels, FullCarModel::kChannels);
    covariance.block(8, 8, 4, 4) = v;
    if (slopes) {
      *slopes = Eigen::MatrixXd::Zero(FullCarModel::kChannels, four.cols());
      slopes->middleRows(8, 4) = four;
    }
    return covariance;
  };
}

Eigen::VectorXd FullCarRoadFreeModel::inputNoiseVariance(const Eigen::VectorXd& absolute,
                                         const Eigen::VectorXd& relative,
                                         double mean_accel_z) const {
  const SampleInputNoise at = inputNoiseBySample(absolute, relative, mean_accel_z);
  return meanVarianceOverSamples([&at](std::size_t k) { return at(k, nullptr); },
                                 inputs_->samples(), FullCarModel::kChannels);
}

}  // namespace pc_ekf
