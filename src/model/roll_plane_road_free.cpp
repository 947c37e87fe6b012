// Road-free roll plane (roll_plane_road_free.h, docs/method.md §4.10).
#include "pc_ekf/model/roll_plane_road_free.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "pc_ekf/model/input_noise.h"
#include "pc_ekf/model/smooth_functions.h"

namespace pc_ekf {

// Per point: what the outputs need (one entry per collocation point).
struct RoadFreeConstants {
  struct Point {
    double k[2], k3[2], damping[2], delta_ref[2];
    double inv_total, inv_inertia, cg, rear_arm, imu_arm;
    double roll_static, gravity, rest_y, rest_z;
  };
  std::vector<Point> points;
  DamperLaw law = DamperLaw::kTanh;
  double tanh_rate = 0.0;
};

namespace {

constexpr int kU1 = 0, kV1 = 2, kGyro = 4;

// phi'' and g + a at the IMU for inputs `in` (u1 u2 v1 v2 [gyro]) and the
// roll since rest `roll`.
double rollAcceleration(const RoadFreeConstants& c, const RoadFreeConstants::Point& p,
                        const double* in, double roll, double* specific) {
  double f[2];
  for (int i = 0; i < 2; ++i) {
    const double x = p.delta_ref[i] - in[kU1 + i];  // spring compression
    const double v = in[kV1 + i];
    const double damper = c.law == DamperLaw::kTanh
                              ? damperForce<DamperLaw::kTanh>(p.damping[i], c.tanh_rate, v)
                              : damperForce<DamperLaw::kLinear>(p.damping[i], c.tanh_rate, v);
    f[i] = p.k[i] * x + p.k3[i] * x * x * x - damper;
  }
  const double theta_dd =
      std::cos(p.roll_static + roll) * (p.rear_arm * f[1] - p.cg * f[0]) * p.inv_inertia;
  *specific = (f[0] + f[1]) * p.inv_total + p.imu_arm * theta_dd;
  return -theta_dd;
}

// The three outputs (accel_y, accel_z, gyro_x) of one point at t, from the
// inputs now and at the previous sample (t - dt), the roll since rest and the
// gyro read at the previous sample.
void outputs(const RoadFreeConstants& c, const RoadFreeConstants::Point& p, const double* now,
             const double* before, bool before_at_rest, double dt, double roll,
             double roll_before, double gyro_before, double* out) {
  double specific = 0.0, specific_before = 0.0;
  const double phi_dd = rollAcceleration(c, p, now, roll, &specific);
  const double phi_dd_before =
      before_at_rest ? 0.0 : rollAcceleration(c, p, before, roll_before, &specific_before);
  const double phi = p.roll_static + roll;
  out[0] = specific * std::sin(phi) - p.rest_y;
  out[1] = specific * std::cos(phi) - p.rest_z;
  out[2] = gyro_before + 0.5 * (phi_dd + phi_dd_before) * dt;
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
  // The suspension's inputs at t - shift; the gyro, the roll integrated from
  // it and the previous sample's instant on the IMU's clock (t).
  void readingsShifted(double t, double shift, Eigen::ArrayXXd& y) const override {
    const int n = in_->count();
    const bool gyro = n > kGyro;
    double now[5] = {0, 0, 0, 0, 0}, before[5] = {0, 0, 0, 0, 0};
    in_->at(t - shift, now);
    const double t_before = in_->previousTime(t);
    const bool at_rest = !(t_before > 0.0);
    double gyro_before = 0.0;
    if (!at_rest) {
      in_->at(t_before - shift, before);
      if (gyro) {
        double own[5] = {0, 0, 0, 0, 0};
        if (shift != 0.0) in_->at(t_before, own);
        gyro_before = shift != 0.0 ? own[kGyro] : before[kGyro];
      }
    }
    const double roll = gyro ? in_->integral(kGyro, t) : 0.0;
    const double roll_before = gyro && !at_rest ? in_->integral(kGyro, t_before) : 0.0;
    double out[3];
    for (Eigen::Index q = 0; q < y.cols(); ++q) {
      outputs(*c_, c_->points[static_cast<std::size_t>(q)], now, before, at_rest, t - t_before,
              roll, roll_before, gyro_before, out);
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
      state_names_{"reading_accel_y", "reading_accel_z", "reading_gyro_x"},
      h_(Eigen::MatrixXd::Zero(RollPlaneModel::kChannels, 3)) {
  if (!inputs_) throw std::invalid_argument("road-free roll plane: no inputs");
  const std::vector<std::string> expected{"u1", "u2", "v1", "v2", "gyro_x"};
  const auto& names = inputs_->names();
  if (names.size() < 4 || names.size() > 5 ||
      !std::equal(names.begin(), names.end(), expected.begin())) {
    throw std::invalid_argument("road-free roll plane: inputs must be u1 u2 v1 v2 [gyro_x]");
  }
  h_.middleRows(4, 3).setIdentity();  // accel_y accel_z gyro_x
  constants(Eigen::MatrixXd(nominal_vector_));  // refuses what it does not model
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
  return (channel == 4 || channel == 6) && inputs_->count() > kGyro;  // the gyro's integral
}

std::unique_ptr<RoadFreeConstants> RollPlaneRoadFreeModel::constants(
    const Eigen::MatrixXd& params) const {
  auto c = std::make_unique<RoadFreeConstants>();
  c->law = nominal_.damper;
  c->tanh_rate = nominal_.damper_tanh_rate;
  const double scale = nominal_.damper == DamperLaw::kTanh ? nominal_.damper_tanh_scale : 1.0;
  for (Eigen::Index q = 0; q < params.cols(); ++q) {
    const std::string why = invalidReason(params.col(q));
    if (!why.empty()) {
      throw std::invalid_argument("road-free roll plane: column " + std::to_string(q) + ": " + why);
    }
  }
  const RollPlaneFields<int>& at = rollPlaneRows();
  for (Eigen::Index q = 0; q < params.cols(); ++q) {
    // Not modelled without a road yet: refused rather than ignored.
    for (int row : {at.body_cg_height, at.added_mass_height, at.imu_height, at.anti_roll_bar}) {
      if (params(row, q) != 0.0) {
        throw std::invalid_argument(
            "road-free roll plane: " + rollPlaneDescription().parameters().names()[row] +
            " must be 0 (heights and the anti-roll bar need a road)");
      }
    }
  }
  const std::vector<StaticEquilibrium> loaded = solveStaticEquilibria(params);
  const bool tare = zero_ == ZeroConvention::kTare;
  std::vector<StaticEquilibrium> unloaded;
  if (tare) {
    Eigen::MatrixXd empty = params;
    empty.row(at.added_mass).setZero();
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
      a.damping[i] = p[at.damping[i]] * scale;
      a.delta_ref[i] = tare ? unloaded[static_cast<std::size_t>(q)].spring_compression[i]
                            : e.spring_compression[i];
    }
    const double position = p[at.added_mass_position];
    const double inertia = p[at.bar_inertia] + p[at.bar_mass] * (0.5 * L - cg) * (0.5 * L - cg) +
                           p[at.added_mass] * (cg - position) * (cg - position);
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
  return c;
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
  const std::vector<int> integrated = n > kGyro ? std::vector<int>{kGyro} : std::vector<int>{};
  return [c, integrated, absolute, relative, n, inputs = inputs_](std::size_t k) {
    const RoadFreeConstants::Point& p = c->points.front();
    const Eigen::MatrixXd v = inputOutputCovarianceAt(
        *inputs, k, absolute, relative, integrated, 3,
        [&](const double* now, const double* before, bool at_rest, double dt, const double* roll,
            double* out) {
          const double gyro_before = n > kGyro ? before[kGyro] : 0.0;
          outputs(*c, p, now, before, at_rest, dt, integrated.empty() ? 0.0 : roll[0], 0.0,
                  gyro_before, out);
        });
    Eigen::MatrixXd covariance =
        Eigen::MatrixXd::Zero(RollPlaneModel::kChannels, RollPlaneModel::kChannels);
    covariance.block(4, 4, 3, 3) = v;
    return covariance;
  };
}

Eigen::VectorXd RollPlaneRoadFreeModel::inputNoiseVariance(const Eigen::VectorXd& absolute,
                                         const Eigen::VectorXd& relative,
                                         double mean_accel_z) const {
  return meanVarianceOverSamples(inputNoiseBySample(absolute, relative, mean_accel_z),
                                 inputs_->samples(), RollPlaneModel::kChannels);
}

}  // namespace pc_ekf
