// Roll-plane vehicle model (SPEC §1): parameter checks and batched right-hand side.
#include "model/roll_plane_model.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "model/smooth_functions.h"

namespace pc_ekf {

namespace {

// Per-point constants, one array per quantity (structure of arrays over the Q points),
// so derivatives() does no equilibrium or parameter work.
struct PointConstants {
  Eigen::ArrayXd k[2], k3[2];        // spring law
  Eigen::ArrayXd three_delta[2];     // 3 delta_i
  Eigen::ArrayXd three_delta_sq[2];  // 3 delta_i^2
  Eigen::ArrayXd damping[2];         // c (linear) or c * tanh scale
  Eigen::ArrayXd tyre[2], inv_unsprung[2];
  Eigen::ArrayXd inv_total_mass;                       // 1 / (m + M)
  Eigen::ArrayXd roll_gain;                            // L / I_cg
  Eigen::ArrayXd cg, rear_arm, cg_ratio;               // D, L - D, D / L
  Eigen::ArrayXd inv_length;                           // 1 / L
  Eigen::ArrayXd roll_static, cos_static, sin_static;  // theta_s, cos and sin of it

  void resize(int q) {
    for (int i = 0; i < 2; ++i) {
      for (Eigen::ArrayXd* a : {&k[i], &k3[i], &three_delta[i], &three_delta_sq[i], &damping[i],
                                &tyre[i], &inv_unsprung[i]}) {
        a->resize(q);
      }
    }
    for (Eigen::ArrayXd* a : {&inv_total_mass, &roll_gain, &cg, &rear_arm, &cg_ratio, &inv_length,
                              &roll_static, &cos_static, &sin_static}) {
      a->resize(q);
    }
  }
};

class RollPlaneBatch : public ModelBatch {
 public:
  RollPlaneBatch(PointConstants c, DamperLaw law, double tanh_rate,
                 std::shared_ptr<const RoadInput> road)
      : c_(std::move(c)), law_(law), tanh_rate_(tanh_rate), road_(std::move(road)) {}

  int pointCount() const override { return static_cast<int>(c_.cg.size()); }

  Eigen::ArrayXXd initialState() const override {
    return Eigen::ArrayXXd::Zero(8, pointCount());  // equilibrium (SPEC §1.4)
  }

  void derivatives(double t, const Eigen::ArrayXXd& y, Eigen::ArrayXXd& dydt) const override {
    if (y.rows() != 8 || y.cols() != pointCount()) {
      throw std::invalid_argument("RollPlaneModel: state batch must be 8 x pointCount()");
    }
    dydt.resize(8, y.cols());  // no-op when already sized
    const Eigen::Vector2d road = road_->height(t);
    if (law_ == DamperLaw::kTanh) {
      evaluate<DamperLaw::kTanh>(road, y, dydt);
    } else {
      evaluate<DamperLaw::kLinear>(road, y, dydt);
    }
  }

 private:
  template <DamperLaw law>
  void evaluate(const Eigen::Vector2d& road, const Eigen::ArrayXXd& y,
                Eigen::ArrayXXd& dydt) const {
    const PointConstants& c = c_;
    for (Eigen::Index q = 0; q < y.cols(); ++q) {
      const double* s = &y(0, q);
      double* d = &dydt(0, q);
      double f[2];
      for (int i = 0; i < 2; ++i) {
        const double u = s[i] - s[2 + i];
        const double v = s[4 + i] - s[6 + i];
        // F_K(delta) - F_K(delta - u) expanded so that it is exactly 0 at u = 0 (SPEC §1.4).
        const double spring =
            u *
            (c.k[i][q] + c.k3[i][q] * (c.three_delta_sq[i][q] - c.three_delta[i][q] * u + u * u));
        const double damper = law == DamperLaw::kTanh ? c.damping[i][q] * fastTanh(tanh_rate_ * v)
                                                      : c.damping[i][q] * v;
        f[i] = -spring - damper;
      }
      // Paper eq. 40-41 solved for the body-end accelerations.
      const double theta = (s[1] - s[0]) * c.inv_length[q];
      const double a_cg = (f[0] + f[1]) * c.inv_total_mass[q];
      const double rel = cosOfSum(c.roll_static[q], c.cos_static[q], c.sin_static[q], theta) *
                         c.roll_gain[q] * (c.rear_arm[q] * f[1] - c.cg[q] * f[0]);  // x2dd - x1dd
      const double a1 = a_cg - rel * c.cg_ratio[q];
      d[0] = s[4];
      d[1] = s[5];
      d[2] = s[6];
      d[3] = s[7];
      d[4] = a1;
      d[5] = a1 + rel;
      // Paper eq. 42-43.
      d[6] = (c.tyre[0][q] * (road[0] - s[2]) - f[0]) * c.inv_unsprung[0][q];
      d[7] = (c.tyre[1][q] * (road[1] - s[3]) - f[1]) * c.inv_unsprung[1][q];
    }
  }

  PointConstants c_;
  DamperLaw law_;
  double tanh_rate_;
  std::shared_ptr<const RoadInput> road_;
};

std::string num(double value) {
  std::ostringstream os;
  os.precision(10);
  os << value;
  return os.str();
}

std::string outOfDomain(const std::string& name, double value, const std::string& why) {
  return name + " = " + num(value) + " " + why;
}

}  // namespace

RollPlaneModel::RollPlaneModel(const VehicleParameters& nominal,
                               std::shared_ptr<const RoadInput> road)
    : nominal_(nominal),
      nominal_vector_(nominal.toVector()),
      h_(Eigen::MatrixXd::Zero(4, 8)),
      road_(std::move(road)) {
  if (!road_) throw std::invalid_argument("RollPlaneModel: no road input");
  const std::string why = invalidReason(nominal_vector_);
  if (!why.empty()) throw std::invalid_argument("RollPlaneModel: nominal parameters: " + why);
  if (nominal_.damper == DamperLaw::kTanh &&
      !(std::isfinite(nominal_.damper_tanh_scale) && std::isfinite(nominal_.damper_tanh_rate) &&
        nominal_.damper_tanh_scale >= 0.0 && nominal_.damper_tanh_rate >= 0.0)) {
    throw std::invalid_argument("RollPlaneModel: damper tanh scale and rate must be finite, >= 0");
  }
  // u_i = x_i - xr_i, v_i = xidot - xridot (SPEC §1.6).
  for (int i = 0; i < 2; ++i) {
    h_(i, i) = 1.0;
    h_(i, 2 + i) = -1.0;
    h_(2 + i, 4 + i) = 1.0;
    h_(2 + i, 6 + i) = -1.0;
  }
}

const std::vector<std::string>& RollPlaneModel::stateNames() const {
  static const std::vector<std::string> names = {"x1",    "x2",    "xr1",    "xr2",
                                                 "x1dot", "x2dot", "xr1dot", "xr2dot"};
  return names;
}

const std::vector<std::string>& RollPlaneModel::parameterNames() const {
  return vehicleParameterNames();
}

const std::vector<std::string>& RollPlaneModel::channelNames() const {
  static const std::vector<std::string> names = {"u1", "u2", "v1", "v2"};
  return names;
}

std::string RollPlaneModel::invalidReason(const Eigen::Ref<const Eigen::VectorXd>& params) const {
  const auto& names = vehicleParameterNames();
  if (params.size() != static_cast<Eigen::Index>(names.size())) {
    return "expected " + std::to_string(names.size()) + " parameters, got " +
           std::to_string(params.size());
  }
  for (Eigen::Index i = 0; i < params.size(); ++i) {
    if (!std::isfinite(params[i])) return outOfDomain(names[i], params[i], "is not finite");
  }
  // Strictly positive: masses, linear stiffnesses, length, inertia, gravity.
  for (int i : {0, 1, 2, 5, 6, 9, 10, 11, 12, 13}) {
    if (params[i] <= 0.0) return outOfDomain(names[i], params[i], "must be > 0");
  }
  for (int i : {3, 4, 7, 8}) {  // damping, cubic stiffness
    if (params[i] < 0.0) return outOfDomain(names[i], params[i], "must be >= 0");
  }
  const double m = params[0], length = params[9], mass = params[14], pos = params[15];
  if (mass + m <= 0.0) {
    return outOfDomain(names[14], mass, "makes the total mass <= 0 (bar_mass = " + num(m) + ")");
  }
  if (pos < 0.0 || pos > length) {
    return outOfDomain(names[15], pos, "outside [0, " + num(length) + "]");
  }
  // A negative added mass can still make the combined inertia non-positive.
  const double cg = (mass * pos + m * 0.5 * length) / (mass + m);
  const double inertia =
      params[10] + m * (0.5 * length - cg) * (0.5 * length - cg) + mass * (cg - pos) * (cg - pos);
  if (!(inertia > 0.0)) {
    return outOfDomain(names[14], mass, "makes the inertia about the combined centre <= 0");
  }
  return "";
}

std::unique_ptr<ModelBatch> RollPlaneModel::prepare(const Eigen::MatrixXd& params) const {
  if (params.rows() != nominal_vector_.size()) {
    throw std::invalid_argument("RollPlaneModel::prepare: expected " +
                                std::to_string(nominal_vector_.size()) + " parameter rows");
  }
  const int count = static_cast<int>(params.cols());
  PointConstants c;
  c.resize(count);
  const double scale = nominal_.damper == DamperLaw::kTanh ? nominal_.damper_tanh_scale : 1.0;
  for (int q = 0; q < count; ++q) {
    const std::string why = invalidReason(params.col(q));
    if (!why.empty()) {
      throw std::invalid_argument("RollPlaneModel::prepare: column " + std::to_string(q) + ": " +
                                  why);
    }
    const VehicleParameters p = VehicleParameters::fromVector(params.col(q), nominal_);
    const StaticEquilibrium e = solveStaticEquilibrium(p);
    const double length = p.bar_length, cg = e.combined_cg, total = p.bar_mass + p.added_mass;
    for (int i = 0; i < 2; ++i) {
      const double delta = e.spring_compression[i];
      c.k[i][q] = p.spring_linear[i];
      c.k3[i][q] = p.spring_cubic[i];
      c.three_delta[i][q] = 3.0 * delta;
      c.three_delta_sq[i][q] = 3.0 * delta * delta;
      c.damping[i][q] = p.damping[i] * scale;
      c.tyre[i][q] = p.tyre_stiffness[i];
      c.inv_unsprung[i][q] = 1.0 / p.unsprung_mass[i];
    }
    // I_cg = I + m (L/2 - D)^2 + M (D - d_CG)^2 (SPEC §1.4).
    const double inertia =
        p.bar_inertia + p.bar_mass * (0.5 * length - cg) * (0.5 * length - cg) +
        p.added_mass * (cg - p.added_mass_position) * (cg - p.added_mass_position);
    c.inv_total_mass[q] = 1.0 / total;
    c.roll_gain[q] = length / inertia;
    c.cg[q] = cg;
    c.rear_arm[q] = length - cg;
    c.cg_ratio[q] = cg / length;
    c.inv_length[q] = 1.0 / length;
    c.roll_static[q] = e.roll_angle;
    c.cos_static[q] = std::cos(e.roll_angle);
    c.sin_static[q] = std::sin(e.roll_angle);
  }
  return std::make_unique<RollPlaneBatch>(std::move(c), nominal_.damper, nominal_.damper_tanh_rate,
                                          road_);
}

std::vector<double> RollPlaneModel::breakpoints(double t0, double t1) const {
  return road_->breakpoints(t0, t1);
}

}  // namespace pc_ekf
