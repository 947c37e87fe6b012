// Road-free roll plane (roll_plane_road_free.h, docs/method.md §4.10).
#include "pc_ekf/model/roll_plane_road_free.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "pc_ekf/model/input_noise.h"
#include "pc_ekf/model/instant_part.h"
#include "pc_ekf/model/smooth_functions.h"

namespace pc_ekf {

// Per point: what the outputs need (one entry per collocation point).
struct RoadFreeConstants {
  struct Point {
    double k[2], k3[2], damping[2], delta_ref[2];
    double inv_total, inv_inertia, cg, rear_arm, imu_arm;
    double roll_static, gravity, rest_y, rest_z;
    // Heights and bar (docs/models.md): k_a, S = m h_b + M h_M, z_I.
    double bar, first_moment, imu_height;
    // ModelBatch::offsetPoints: added to the roll and to a_y (0: none).
    double roll_offset, lateral_offset;
  };
  std::vector<Point> points;
  DamperLaw law = DamperLaw::kTanh;
  double tanh_rate = 0.0;
  DamperCurve curve[2];  // law kTable: damping holds c / c_ref
  // Where the optional inputs are (-1: not read): the gyro, and speed and
  // yaw rate, whose product is the lateral acceleration a_y.
  int gyro = -1, speed = -1, yaw = -1;
  // Some point has heights, a bar or an IMU height, or a_y is read: the
  // general outputs (else the paper's, bit for bit).
  bool elevated = false;
  bool elevated_points = false;  // elevated as constants() found it (before any offsets)
};

namespace {

constexpr int kU1 = 0, kV1 = 2, kMaxInputs = 7;  // u1 u2 v1 v2 [gyro_x] [speed gyro_z]

// a_y = speed x yaw rate from the inputs (0 when they are not read).
// Plus the point's lateral offset (a cross-fall's g sin(beta)).
double lateralOf(const RoadFreeConstants& c, const RoadFreeConstants::Point& p, const double* in) {
  double a = c.speed < 0 ? 0.0 : in[c.speed] * in[c.yaw];
  if (p.lateral_offset != 0.0) a += p.lateral_offset;  // (0: today's bit for bit)
  return a;
}

// The spring's compression x_i and the spring minus damper force f_i of
// each side for inputs `in`.
inline void springDamperForces(const RoadFreeConstants& c, const RoadFreeConstants::Point& p,
                               const double* in, double* x, double* f) {
  for (int i = 0; i < 2; ++i) {
    x[i] = p.delta_ref[i] - in[kU1 + i];  // spring compression
    const double v = in[kV1 + i];
    const double damper =
        c.law == DamperLaw::kTanh    ? damperForce<DamperLaw::kTanh>(p.damping[i], c.tanh_rate, v)
        : c.law == DamperLaw::kTable ? p.damping[i] * c.curve[i](v)
                                     : damperForce<DamperLaw::kLinear>(p.damping[i], c.tanh_rate, v);
    f[i] = p.k[i] * x[i] + p.k3[i] * x[i] * x[i] * x[i] - damper;
  }
}

// phi'' and g + a at the IMU for inputs `in` and the roll since rest `roll`.
// With heights, bar or a_y (docs/models.md): the bar's force k_a (x1 - x2)
// on the left end (x the compressions), minus it on the right, and
// J phi'' = cos(phi) (D F_1 - (L - D) F_2) + S (a_y cos(phi) + (g + a_P) sin(phi))
// with the total forces F_i (their static part carries the S g tan(phi_s)).
double rollAcceleration(const RoadFreeConstants& c, const RoadFreeConstants::Point& p,
                        const double* in, double roll, double* specific) {
  double f[2], x[2];
  springDamperForces(c, p, in, x, f);
  if (!c.elevated) {
    const double theta_dd =
        std::cos(p.roll_static + roll) * (p.rear_arm * f[1] - p.cg * f[0]) * p.inv_inertia;
    *specific = (f[0] + f[1]) * p.inv_total + p.imu_arm * theta_dd;
    return -theta_dd;
  }
  const double twist = p.bar * (x[0] - x[1]);
  f[0] += twist;
  f[1] -= twist;
  const double phi = p.roll_static + roll, cos_phi = std::cos(phi);
  const double specific_p = (f[0] + f[1]) * p.inv_total;  // g + a_P
  const double phi_dd =
      (cos_phi * (p.cg * f[0] - p.rear_arm * f[1]) +
       p.first_moment * (lateralOf(c, p, in) * cos_phi + specific_p * std::sin(phi))) *
      p.inv_inertia;
  *specific = specific_p - p.imu_arm * phi_dd;
  return phi_dd;
}

// The three outputs (accel_y, accel_z, gyro_x) of one point at t, from the
// inputs now and at the previous sample (t - dt), the roll since rest and the
// gyro read at the previous sample.
// One instant's roll acceleration and specific force, kept by the input
// slopes (instant_part.h).
struct RollPart {
  double phi_dd = 0.0, specific = 0.0;
};
using RollParts = OutputParts<kMaxInputs, 1, RollPart>;
using RollInstant = InstantPart<kMaxInputs, 1, RollPart>;

// phi'' at one instant, from `parts` when it holds that instant's inputs.
double instantRoll(const RoadFreeConstants& c, const RoadFreeConstants::Point& p, const double* in,
                   double roll, double* specific, RollInstant* part, int count) {
  const double angles[1] = {roll};
  if (part && part->same(in, count, angles)) {
    *specific = part->part.specific;
    return part->part.phi_dd;
  }
  const double phi_dd = rollAcceleration(c, p, in, roll, specific);
  if (part) part->keep(in, count, angles, RollPart{phi_dd, *specific});
  return phi_dd;
}

void outputs(const RoadFreeConstants& c, const RoadFreeConstants::Point& p, const double* now,
             const double* before, bool before_at_rest, double dt, double roll,
             double roll_before, double gyro_before, double* out, RollParts* parts = nullptr) {
  double specific = 0.0, specific_before = 0.0;
  const int count = parts ? parts->count : 0;
  const double phi_dd =
      instantRoll(c, p, now, roll, &specific, parts ? &parts->now : nullptr, count);
  const double phi_dd_before =
      before_at_rest ? 0.0
                     : instantRoll(c, p, before, roll_before, &specific_before,
                                   parts ? &parts->before : nullptr, count);
  const double phi = p.roll_static + roll;
  out[2] = gyro_before + 0.5 * (phi_dd + phi_dd_before) * dt;
  if (c.elevated) {
    // The tilted a_y and the IMU's height z_I (phi' the gyro read, when it is).
    const double a_y = lateralOf(c, p, now), rate = c.gyro < 0 ? 0.0 : now[c.gyro];
    out[0] = a_y * std::cos(phi) + specific * std::sin(phi) - p.imu_height * phi_dd - p.rest_y;
    out[1] = specific * std::cos(phi) - a_y * phi - p.imu_height * rate * rate - p.rest_z;
    return;
  }
  out[0] = specific * std::sin(phi) - p.rest_y;
  out[1] = specific * std::cos(phi) - p.rest_z;
}

class RoadFreeBatch : public ModelBatch {
 public:
  RoadFreeBatch(std::unique_ptr<RoadFreeConstants> c, std::shared_ptr<const ReadingInputs> in)
      : c_(std::move(c)), in_(std::move(in)) {}
  int pointCount() const override { return static_cast<int>(c_->points.size()); }
  void derivatives(double, const Eigen::ArrayXXd& y, Eigen::ArrayXXd& dydt) const override {
    dydt.resize(y.rows(), y.cols());  // no dynamic state
  }
  Eigen::ArrayXXd initialState() const override {
    Eigen::ArrayXXd y(3, pointCount());
    for (Eigen::Index q = 0; q < y.cols(); ++q) {
      const RoadFreeConstants::Point& p = c_->points[static_cast<std::size_t>(q)];
      y(0, q) = p.gravity * std::sin(p.roll_static) - p.rest_y;  // at rest
      y(1, q) = p.gravity * std::cos(p.roll_static) - p.rest_z;
      y(2, q) = 0.0;
    }
    return y;
  }
  void readings(double t, Eigen::ArrayXXd& y) const override { readingsShifted(t, 0.0, y); }
  bool offsetPoints(const Eigen::VectorXd& roll, const Eigen::VectorXd& lateral) override {
    if (c_->gyro < 0 || roll.size() != pointCount() || lateral.size() != pointCount()) return false;
    // Offsets replace earlier ones (a batch prepared once, offset per sample).
    c_->elevated = c_->elevated_points;
    for (int q = 0; q < pointCount(); ++q) {
      RoadFreeConstants::Point& p = c_->points[static_cast<std::size_t>(q)];
      p.roll_offset = roll[q];
      p.lateral_offset = lateral[q];
      if (p.lateral_offset != 0.0) c_->elevated = true;  // a_y's terms
    }
    return true;
  }
  // The suspension's inputs (and speed and yaw rate, which drive the body) at
  // t - shift; the gyro, the roll integrated from it and the previous
  // sample's instant on the IMU's clock (t).
  void readingsShifted(double t, double shift, Eigen::ArrayXXd& y) const override {
    const int gyro_at = c_->gyro;
    const bool gyro = gyro_at >= 0;
    double now[kMaxInputs] = {}, before[kMaxInputs] = {};
    in_->at(t - shift, now);
    const double t_before = in_->previousTime(t);
    const bool at_rest = !(t_before > 0.0);
    double gyro_before = 0.0;
    if (!at_rest) {
      in_->at(t_before - shift, before);
      if (gyro) {
        double own[kMaxInputs] = {};
        if (shift != 0.0) in_->at(t_before, own);
        gyro_before = shift != 0.0 ? own[gyro_at] : before[gyro_at];
      }
    }
    const double roll = gyro ? in_->integral(gyro_at, t) : 0.0;
    const double roll_before = gyro && !at_rest ? in_->integral(gyro_at, t_before) : 0.0;
    double out[3];
    for (Eigen::Index q = 0; q < y.cols(); ++q) {
      const RoadFreeConstants::Point& p = c_->points[static_cast<std::size_t>(q)];
      if (p.roll_offset != 0.0) {  // (0: today's values bit for bit)
        outputs(*c_, p, now, before, at_rest, t - t_before, roll + p.roll_offset,
                roll_before + p.roll_offset, gyro_before, out);
      } else {
        outputs(*c_, p, now, before, at_rest, t - t_before, roll, roll_before, gyro_before, out);
      }
      for (int r = 0; r < 3; ++r) y(r, q) = out[r];
    }
  }

 private:
  std::unique_ptr<RoadFreeConstants> c_;
  std::shared_ptr<const ReadingInputs> in_;
};

}  // namespace

RollPlaneRoadFreeModel::RollPlaneRoadFreeModel(const VehicleParameters& nominal,
                                               std::shared_ptr<const ReadingInputs> inputs,
                                               ZeroConvention zero)
    : nominal_(nominal),
      with_road_(nominal, std::make_shared<SineRoad>(SineSettings{0.0, 1.0, -1.0})),
      inputs_(std::move(inputs)),
      zero_(zero),
      nominal_vector_(nominal.toVector()),
      state_names_{"reading_" + rollPlaneChannels()[4], "reading_" + rollPlaneChannels()[5],
                   "reading_" + rollPlaneChannels()[kGyroChannel]},
      h_(Eigen::MatrixXd::Zero(RollPlaneModel::kChannels, 3)) {
  if (!inputs_) throw std::invalid_argument("road-free roll plane: no inputs");
  // u1 u2 v1 v2, then gyro_x, speed and gyro_z when read (speed with gyro_z).
  const std::vector<std::string>& ch = rollPlaneChannels();
  const std::vector<std::string> suspension(ch.begin(),
                                            ch.begin() + RollPlaneModel::kSuspensionChannels);
  std::vector<std::string> names = inputs_->names();
  const auto position = [&](const std::string& name) {
    const auto it = std::find(names.begin(), names.end(), name);
    return it == names.end() ? -1 : static_cast<int>(it - names.begin());
  };
  gyro_ = position(ch[kGyroChannel]);
  speed_ = position(ch[kSpeedChannel]);
  yaw_ = position(ch[kYawChannel]);
  std::vector<std::string> expected = suspension;
  if (gyro_ >= 0) expected.push_back(ch[kGyroChannel]);
  if (speed_ >= 0 || yaw_ >= 0) {
    expected.push_back(ch[kSpeedChannel]);
    expected.push_back(ch[kYawChannel]);
  }
  if (names != expected) {
    throw std::invalid_argument(
        "road-free roll plane: inputs must be u1 u2 v1 v2 [gyro_x] [speed gyro_z]");
  }
  h_.middleRows(4, 3).setIdentity();  // accel_y accel_z gyro_x
  // With tare the record weighs the load (inputNoiseBySample): the springs'
  // force at the nominal vehicle, summed over the samples as they come.
  if (zero_ == ZeroConvention::kTare) {
    const RoadFreeConstants::Point p0 = constants(Eigen::MatrixXd(nominal_vector_))->points.front();
    spring_force_sum_ = inputs_->addSampleSum([p0](const double* in) {
      double f = 0.0;
      for (int i = 0; i < 2; ++i) {
        const double x = p0.delta_ref[i] - in[kU1 + i];
        f += p0.k[i] * x + p0.k3[i] * x * x * x;
      }
      return f;
    });
  }
}

bool RollPlaneRoadFreeModel::channelModelled(int channel) const {
  if (channel == 5) return true;  // accel_z needs the suspension readings only
  return (channel == 4 || channel == 6) && gyro_ >= 0;  // the gyro's integral
}

bool RollPlaneRoadFreeModel::channelIsInput(int channel) const {
  return channel < 4 || (speed_ >= 0 && (channel == kSpeedChannel || channel == kYawChannel));
}

std::unique_ptr<RoadFreeConstants> RollPlaneRoadFreeModel::constants(
    const Eigen::MatrixXd& params) const {
  auto c = std::make_unique<RoadFreeConstants>();
  c->law = nominal_.damper;
  c->tanh_rate = nominal_.damper_tanh_rate;
  double scale[2] = {1.0, 1.0};
  for (int i = 0; i < 2; ++i) {
    if (nominal_.damper == DamperLaw::kTanh) scale[i] = nominal_.damper_tanh_scale;
    if (nominal_.damper == DamperLaw::kTable) {
      c->curve[i] = nominal_.damper_curve[i];
      scale[i] = 1.0 / c->curve[i].referenceDamping();
    }
  }
  for (Eigen::Index q = 0; q < params.cols(); ++q) {
    const std::string why = invalidReason(params.col(q));
    if (!why.empty()) {
      throw std::invalid_argument("road-free roll plane: column " + std::to_string(q) + ": " + why);
    }
  }
  const RollPlaneFields<int>& at = rollPlaneRows();
  c->gyro = gyro_;
  c->speed = speed_;
  c->yaw = yaw_;
  c->elevated = speed_ >= 0;
  c->points.reserve(static_cast<std::size_t>(params.cols()));
  const std::vector<StaticEquilibrium> loaded = solveStaticEquilibria(params);
  const bool tare = zero_ == ZeroConvention::kTare;
  std::vector<StaticEquilibrium> unloaded;
  if (tare) {
    Eigen::MatrixXd empty = params;
    empty.row(at.added_mass).setZero();
    // Without the load its place and height do not matter (0 M exactly): held
    // at the first column's, the steps in them share its solution.
    empty.row(at.added_mass_position).setConstant(params(at.added_mass_position, 0));
    empty.row(at.added_mass_height).setConstant(params(at.added_mass_height, 0));
    unloaded = solveStaticEquilibria(empty);
  }
  for (Eigen::Index q = 0; q < params.cols(); ++q) {
    const double* p = &params(0, q);
    const StaticEquilibrium& e = loaded[static_cast<std::size_t>(q)];
    RoadFreeConstants::Point a{};
    const double total = p[at.bar_mass] + p[at.added_mass], cg = e.combined_cg,
                 L = p[at.bar_length];
    for (int i = 0; i < 2; ++i) {
      a.k[i] = p[at.spring_linear[i]];
      a.k3[i] = p[at.spring_cubic[i]];
      a.damping[i] = p[at.damping[i]] * scale[i];
      a.delta_ref[i] = tare ? unloaded[static_cast<std::size_t>(q)].spring_compression[i]
                            : e.spring_compression[i];
    }
    const double position = p[at.added_mass_position];
    const double body = 0.5 * L - p[at.body_cg_offset];  // the body's centre from the left end
    double inertia = p[at.bar_inertia] + p[at.bar_mass] * (body - cg) * (body - cg) +
                     p[at.added_mass] * (cg - position) * (cg - position);
    const double h_b = p[at.body_cg_height], h_m = p[at.added_mass_height];
    a.bar = p[at.anti_roll_bar];
    a.first_moment = p[at.bar_mass] * h_b + p[at.added_mass] * h_m;
    a.imu_height = p[at.imu_height];
    if (h_b != 0.0 || h_m != 0.0 || a.bar != 0.0 || a.imu_height != 0.0) {
      c->elevated = true;
      inertia += p[at.bar_mass] * h_b * h_b + p[at.added_mass] * h_m * h_m;  // J
    }
    a.inv_total = 1.0 / total;
    a.inv_inertia = 1.0 / inertia;
    a.cg = cg;
    a.rear_arm = L - cg;
    a.imu_arm = p[at.imu_position] - cg;
    a.roll_static = -e.roll_angle;
    a.gravity = p[at.gravity];
    a.rest_y = tare ? 0.0 : p[at.gravity] * std::sin(a.roll_static);
    a.rest_z = tare ? 0.0 : p[at.gravity] * std::cos(a.roll_static);
    c->points.push_back(a);
  }
  c->elevated_points = c->elevated;
  return c;
}

double RollPlaneRoadFreeModel::loadTransferRatio(const Eigen::VectorXd& params, double t) const {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (params.size() != nominal_vector_.size() || !params.allFinite()) return nan;
  std::unique_ptr<RoadFreeConstants> c;
  try {
    c = constants(Eigen::MatrixXd(params));
  } catch (const std::exception&) {
    return nan;  // not admissible, or no static equilibrium
  }
  const RoadFreeConstants::Point& p = c->points.front();
  double in[kMaxInputs] = {}, x[2], f[2];
  inputs_->at(t, in);
  springDamperForces(*c, p, in, x, f);
  const double twist = p.bar * (x[0] - x[1]);
  const RollPlaneFields<int>& at = rollPlaneRows();
  double left = f[0] + twist + params[at.unsprung_mass[0]] * p.gravity;
  double right = f[1] - twist + params[at.unsprung_mass[1]] * p.gravity;
  // a_y's share that bypasses the springs: the body and load's lateral force
  // at the mount plane and the unsprung masses' at the wheel centres.
  const double a_y = c->speed < 0 ? 0.0 : lateralOf(*c, p, in);
  if (a_y != 0.0) {
    const double lever = (params[at.bar_mass] + params[at.added_mass]) * params[at.mount_height] +
                         (params[at.unsprung_mass[0]] + params[at.unsprung_mass[1]]) *
                             params[at.wheel_radius];
    const double shift = a_y * lever / params[at.bar_length];
    left -= shift;
    right += shift;
  }
  return (right - left) / (right + left);
}

std::unique_ptr<ModelBatch> RollPlaneRoadFreeModel::prepare(const Eigen::MatrixXd& params) const {
  if (params.rows() != nominal_vector_.size()) {
    throw std::invalid_argument("road-free roll plane: expected " +
                                std::to_string(nominal_vector_.size()) + " parameter rows");
  }
  return std::make_unique<RoadFreeBatch>(constants(params), inputs_);
}

MechanicalModel::SampleInputNoise RollPlaneRoadFreeModel::inputNoiseBySample(const Eigen::VectorXd& absolute,
                                                           const Eigen::VectorXd& relative,
                                                           double mean_accel_z) const {
  const int n = inputs_->count();
  if (absolute.size() != n || relative.size() != n) {
    throw std::invalid_argument("inputNoiseBySample: one std per input");
  }
  Eigen::VectorXd vehicle = nominal_vector_;
  // With tare the record weighs the load (the derivatives scale with 1 / (m + M)).
  if (zero_ == ZeroConvention::kTare) {
    const int m = rollPlaneDescription().parameters().at("bar_mass");
    const int added = rollPlaneDescription().parameters().at("added_mass");
    vehicle[added] = weighedLoad(*inputs_, spring_force_sum_, mean_accel_z, vehicle[m],
                                 4.0 * std::max(vehicle[added], vehicle[m]), vehicle[added]);
  }
  std::shared_ptr<const RoadFreeConstants> c = constants(Eigen::MatrixXd(vehicle));
  const int gyro = gyro_;
  const std::vector<int> integrated = gyro >= 0 ? std::vector<int>{gyro} : std::vector<int>{};
  return [c, integrated, absolute, relative, gyro, inputs = inputs_](std::size_t k, Eigen::MatrixXd* slopes) {
    const RoadFreeConstants::Point& p = c->points.front();
    Eigen::MatrixXd three;
    RollParts parts;
    parts.count = std::min(inputs->count(), kMaxInputs);
    const Eigen::MatrixXd v = inputOutputCovarianceAt(
        *inputs, k, absolute, relative, integrated, 3,
        [&](const double* now, const double* before, bool at_rest, double dt, const double* roll,
            double* out) {
          const double gyro_before = gyro >= 0 ? before[gyro] : 0.0;
          outputs(*c, p, now, before, at_rest, dt, integrated.empty() ? 0.0 : roll[0], 0.0,
                  gyro_before, out, &parts);
        },
        slopes ? &three : nullptr);
    Eigen::MatrixXd covariance =
        Eigen::MatrixXd::Zero(RollPlaneModel::kChannels, RollPlaneModel::kChannels);
    covariance.block(4, 4, 3, 3) = v;
    if (slopes) {
      *slopes = Eigen::MatrixXd::Zero(RollPlaneModel::kChannels, three.cols());
      slopes->middleRows(4, 3) = three;
    }
    return covariance;
  };
}

Eigen::VectorXd RollPlaneRoadFreeModel::inputNoiseVariance(const Eigen::VectorXd& absolute,
                                         const Eigen::VectorXd& relative,
                                         double mean_accel_z) const {
  const SampleInputNoise at = inputNoiseBySample(absolute, relative, mean_accel_z);
  return meanVarianceOverSamples([&at](std::size_t k) { return at(k, nullptr); },
                                 inputs_->samples(), RollPlaneModel::kChannels);
}

}  // namespace pc_ekf
