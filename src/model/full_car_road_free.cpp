// Road-free full car (full_car_road_free.h, docs/method.md §4.10).
#include "pc_ekf/model/full_car_road_free.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "pc_ekf/model/input_noise.h"
#include "pc_ekf/model/smooth_functions.h"

namespace pc_ekf {

struct FullCarRoadFreeConstants {
  struct Point {
    double x[4], y[4], k[4], k3[4], damping[4], delta_ref[4];
    Eigen::Matrix3d inv_mass;
    Eigen::Vector3d weight;  // (m_s + M) g, M x_M g, M y_M g
    double imu_x, imu_y, roll_static, pitch_static, gravity, rest_y, rest_z;
  };
  std::vector<Point> points;
  DamperLaw law = DamperLaw::kTanh;
  double tanh_rate = 0.0;
};

namespace {

constexpr int kGyroX = 8, kGyroY = 9;

// (z'', theta'', phi'') for inputs `in`; *specific = g + a at the IMU.
Eigen::Vector3d bodyAcceleration(const FullCarRoadFreeConstants& c,
                                 const FullCarRoadFreeConstants::Point& p, const double* in,
                                 double* specific) {
  Eigen::Vector3d load = -p.weight;
  for (int i = 0; i < 4; ++i) {
    const double x = p.delta_ref[i] - in[i];
    const double v = in[4 + i];
    const double damper = c.law == DamperLaw::kTanh
                              ? damperForce<DamperLaw::kTanh>(p.damping[i], c.tanh_rate, v)
                              : damperForce<DamperLaw::kLinear>(p.damping[i], c.tanh_rate, v);
    const double f = p.k[i] * x + p.k3[i] * x * x * x - damper;
    load += f * Eigen::Vector3d(1.0, p.x[i], p.y[i]);
  }
  const Eigen::Vector3d q = p.inv_mass * load;
  *specific = p.gravity + q[0] + p.imu_x * q[1] + p.imu_y * q[2];
  return q;
}

// gyro_before: the gyros' readings at the previous sample (x, y).
void outputs(const FullCarRoadFreeConstants& c, const FullCarRoadFreeConstants::Point& p,
             const double* now, const double* before, bool before_at_rest, double dt,
             double roll, double pitch, const double* gyro_before, double* out) {
  double specific = 0.0, unused = 0.0;
  const Eigen::Vector3d a = bodyAcceleration(c, p, now, &specific);
  const Eigen::Vector3d b =
      before_at_rest ? Eigen::Vector3d::Zero() : bodyAcceleration(c, p, before, &unused);
  const double r = p.roll_static + roll, pt = p.pitch_static + pitch;
  out[0] = specific * std::cos(pt) * std::sin(r) - p.rest_y;
  out[1] = specific * std::cos(pt) * std::cos(r) - p.rest_z;
  out[2] = (before_at_rest ? 0.0 : gyro_before[0]) + 0.5 * (a[2] + b[2]) * dt;
  out[3] = (before_at_rest ? 0.0 : gyro_before[1]) - 0.5 * (a[1] + b[1]) * dt;
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
    const bool gyros = in_->count() > kGyroY;
    double now[10] = {}, before[10] = {};
    in_->at(t, now);
    const double t_before = in_->previousTime(t);
    const bool at_rest = !(t_before > 0.0);
    if (!at_rest) in_->at(t_before, before);
    const double roll = gyros ? in_->integral(kGyroX, t) : 0.0;
    // REP 103 pitch since rest (nose down > 0): gyro_y's integral, as the
    // full model's pitch_static - theta.
    const double pitch = gyros ? in_->integral(kGyroY, t) : 0.0;
    const double gyro_before[2] = {before[kGyroX], before[kGyroY]};
    double out[4];
    for (Eigen::Index q = 0; q < y.cols(); ++q) {
      outputs(*c_, c_->points[static_cast<std::size_t>(q)], now, before, at_rest, t - t_before,
              roll, pitch, gyro_before, out);
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
      h_(Eigen::MatrixXd::Zero(12, 4)) {
  if (!inputs_) throw std::invalid_argument("road-free full car: no inputs");
  const std::vector<std::string> expected{"u_fl", "u_fr", "u_rl", "u_rr", "v_fl",
                                          "v_fr", "v_rl", "v_rr", "gyro_x", "gyro_y"};
  const auto& names = inputs_->names();
  if ((names.size() != 8 && names.size() != 10) ||
      !std::equal(names.begin(), names.end(), expected.begin())) {
    throw std::invalid_argument(
        "road-free full car: inputs must be u_fl .. u_rr, v_fl .. v_rr [gyro_x gyro_y]");
  }
  h_.bottomRows(4).setIdentity();
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
  return channel >= 8 && channel <= 11 && inputs_->count() > kGyroY;
}

std::unique_ptr<FullCarRoadFreeConstants> FullCarRoadFreeModel::constants(
    const Eigen::MatrixXd& params) const {
  auto c = std::make_unique<FullCarRoadFreeConstants>();
  c->law = nominal_.damper;
  c->tanh_rate = nominal_.damper_tanh_rate;
  const double scale = nominal_.damper == DamperLaw::kTanh ? nominal_.damper_tanh_scale : 1.0;
  const bool tare = zero_ == ZeroConvention::kTare;
  for (Eigen::Index q = 0; q < params.cols(); ++q) {
    const std::string why = invalidReason(params.col(q));
    if (!why.empty()) {
      throw std::invalid_argument("road-free full car: column " + std::to_string(q) + ": " + why);
    }
    const FullCarColumn p(&params(0, q));
    const FullCarFields<int>& at = p.at();
    const FullCarEquilibrium e = solveFullCarEquilibrium(p);
    FullCarEquilibrium e0;
    if (tare) {
      Eigen::VectorXd empty = params.col(q);
      empty[at.added_mass] = 0.0;
      e0 = solveFullCarEquilibrium(FullCarColumn(empty.data()));
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
    a.inv_mass = p.bodyMass().inverse();
    a.weight = Eigen::Vector3d((p[at.body_mass] + m) * g, m * xm * g, m * ym * g);
    a.imu_x = p[at.imu_x];
    a.imu_y = p[at.imu_y];
    a.roll_static = e.roll;
    a.pitch_static = -e.pitch;
    a.gravity = g;
    const double level = g * std::cos(a.pitch_static);
    a.rest_y = tare ? 0.0 : level * std::sin(a.roll_static);
    a.rest_z = tare ? 0.0 : level * std::cos(a.roll_static);
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
  const bool gyros = n > kGyroY;
  const std::vector<int> integrated = gyros ? std::vector<int>{kGyroX, kGyroY} : std::vector<int>{};
  return [c, integrated, absolute, relative, gyros, inputs = inputs_](std::size_t k) {
    const auto& p = c->points.front();
    const Eigen::MatrixXd v = inputOutputCovarianceAt(
        *inputs, k, absolute, relative, integrated, 4,
        [&](const double* now, const double* before, bool at_rest, double dt, const double* angle,
            double* out) {
          const double gyro_before[2] = {gyros ? before[kGyroX] : 0.0, gyros ? before[kGyroY] : 0.0};
          outputs(*c, p, now, before, at_rest, dt, gyros ? angle[0] : 0.0, gyros ? -angle[1] : 0.0,
                  gyro_before, out);
        });
    Eigen::MatrixXd covariance = Eigen::MatrixXd::Zero(12, 12);
    covariance.bottomRightCorner(4, 4) = v;
    return covariance;
  };
}

Eigen::VectorXd FullCarRoadFreeModel::inputNoiseVariance(const Eigen::VectorXd& absolute,
                                         const Eigen::VectorXd& relative,
                                         double mean_accel_z) const {
  return meanVarianceOverSamples(inputNoiseBySample(absolute, relative, mean_accel_z),
                                 inputs_->samples(), 12);
}

}  // namespace pc_ekf
