// Full-car ride model: parameter checks and the batched right-hand side.
#include "model/full_car_model.h"

#include <cmath>
#include <stdexcept>
#include <utility>

#include "model/smooth_functions.h"

namespace pc_ekf {

namespace {

// Per-point constants, so derivatives() does no equilibrium or parameter work.
struct CornerConstants {
  double x, y;                          // position relative to O
  double k, k3, three_delta, three_delta_sq;  // spring law about the static compression
  double damping;                       // c (linear) or c * tanh scale
  double inv_unsprung;
};
struct PointConstants {
  CornerConstants corner[4];
  double tyre;
  Eigen::Matrix3d inv_body_mass;  // M_b^-1 for q = (z, theta, phi)
};

// F_K(delta) - F_K(delta - u), expanded so that it is exactly 0 at u = 0.
inline double springIncrement(double u, const CornerConstants& c) {
  return u * (c.k + c.k3 * (c.three_delta_sq - c.three_delta * u + u * u));
}

template <DamperLaw law>
void pointDerivatives(const PointConstants& p, double tanh_rate, const double road[4],
                      const double* s, double* d) {
  double f[4];
  double gen[3] = {0.0, 0.0, 0.0};  // generalised force on (z, theta, phi)
  for (int i = 0; i < 4; ++i) {
    const CornerConstants& c = p.corner[i];
    const double u = s[0] + c.x * s[1] + c.y * s[2] - s[3 + i];
    const double v = s[7] + c.x * s[8] + c.y * s[9] - s[10 + i];
    const double damper =
        law == DamperLaw::kTanh ? c.damping * fastTanh(tanh_rate * v) : c.damping * v;
    f[i] = -springIncrement(u, c) - damper;
    gen[0] += f[i];
    gen[1] += f[i] * c.x;
    gen[2] += f[i] * c.y;
  }
  for (int i = 0; i < 7; ++i) d[i] = s[7 + i];
  for (int r = 0; r < 3; ++r) {
    d[7 + r] = p.inv_body_mass(r, 0) * gen[0] + p.inv_body_mass(r, 1) * gen[1] +
               p.inv_body_mass(r, 2) * gen[2];
  }
  for (int i = 0; i < 4; ++i) {
    d[10 + i] = (p.tyre * (road[i] - s[3 + i]) - f[i]) * p.corner[i].inv_unsprung;
  }
}

class FullCarBatch : public ModelBatch {
 public:
  FullCarBatch(std::vector<PointConstants> points, DamperLaw law, double tanh_rate,
               std::shared_ptr<const ContactRoad> road)
      : points_(std::move(points)), law_(law), tanh_rate_(tanh_rate), road_(std::move(road)) {}

  int pointCount() const override { return static_cast<int>(points_.size()); }

  Eigen::ArrayXXd initialState() const override {
    return Eigen::ArrayXXd::Zero(14, pointCount());  // the static equilibrium
  }

  void derivatives(double t, const Eigen::ArrayXXd& y, Eigen::ArrayXXd& dydt) const override {
    if (y.rows() != 14 || y.cols() != pointCount()) {
      throw std::invalid_argument("FullCarModel: state batch must be 14 x pointCount()");
    }
    dydt.resize(14, y.cols());
    Eigen::Vector4d road;
    road_->heights(t, road);
    for (Eigen::Index q = 0; q < y.cols(); ++q) {
      if (law_ == DamperLaw::kTanh) {
        pointDerivatives<DamperLaw::kTanh>(points_[q], tanh_rate_, road.data(), &y(0, q),
                                           &dydt(0, q));
      } else {
        pointDerivatives<DamperLaw::kLinear>(points_[q], tanh_rate_, road.data(), &y(0, q),
                                             &dydt(0, q));
      }
    }
  }

 private:
  std::vector<PointConstants> points_;
  DamperLaw law_;
  double tanh_rate_;
  std::shared_ptr<const ContactRoad> road_;
};

PointConstants constantsOf(const FullCarParameters& p, const FullCarEquilibrium& e,
                           double damper_scale) {
  PointConstants c;
  for (int i = 0; i < 4; ++i) {
    const int axle = FullCarParameters::axle(i);
    CornerConstants& k = c.corner[i];
    const double delta = e.spring_compression[i];
    k.x = p.cornerX(i);
    k.y = p.cornerY(i);
    k.k = p.spring_linear[axle];
    k.k3 = p.spring_cubic[axle];
    k.three_delta = 3.0 * delta;
    k.three_delta_sq = 3.0 * delta * delta;
    k.damping = p.damping[axle] * damper_scale;
    k.inv_unsprung = 1.0 / p.unsprung_mass[axle];
  }
  c.tyre = p.tyre_stiffness;
  // M is a point mass at (x_M, y_M) at the height of O: it moves with z + x_M theta + y_M phi.
  const double m = p.added_mass, xm = p.addedMassX(), ym = p.addedMassY();
  Eigen::Matrix3d mb;
  mb << p.body_mass + m, m * xm, m * ym,
        m * xm, p.pitch_inertia + m * xm * xm, m * xm * ym,
        m * ym, m * xm * ym, p.roll_inertia + m * ym * ym;
  c.inv_body_mass = mb.inverse();
  return c;
}

}  // namespace

FullCarModel::FullCarModel(const FullCarParameters& nominal,
                           std::shared_ptr<const ContactRoad> road)
    : nominal_(nominal),
      nominal_vector_(nominal.toVector()),
      h_(Eigen::MatrixXd::Zero(8, 14)),
      road_(std::move(road)) {
  if (!road_) throw std::invalid_argument("FullCarModel: no road input");
  if (road_->contactCount() != 4) {
    throw std::invalid_argument("FullCarModel: the road must have 4 contacts, got " +
                                std::to_string(road_->contactCount()));
  }
  const std::string why = invalidReason(nominal_vector_);
  if (!why.empty()) throw std::invalid_argument("FullCarModel: nominal parameters: " + why);
  if (nominal_.damper == DamperLaw::kTanh &&
      !(std::isfinite(nominal_.damper_tanh_scale) && std::isfinite(nominal_.damper_tanh_rate) &&
        nominal_.damper_tanh_scale >= 0.0 && nominal_.damper_tanh_rate >= 0.0)) {
    throw std::invalid_argument("FullCarModel: damper tanh scale and rate must be finite, >= 0");
  }
  // u_i = z + x_i theta + y_i phi - zu_i and its rate, with the nominal geometry.
  for (int i = 0; i < 4; ++i) {
    const double x = nominal_.cornerX(i), y = nominal_.cornerY(i);
    for (int rate = 0; rate < 2; ++rate) {
      const int row = 4 * rate + i, col = 7 * rate;
      h_(row, col) = 1.0;
      h_(row, col + 1) = x;
      h_(row, col + 2) = y;
      h_(row, col + 3 + i) = -1.0;
    }
  }
}

const std::vector<std::string>& FullCarModel::stateNames() const {
  static const std::vector<std::string> names = {
      "z",    "theta",    "phi",    "zu_fl",    "zu_fr",    "zu_rl",    "zu_rr",
      "zdot", "thetadot", "phidot", "zudot_fl", "zudot_fr", "zudot_rl", "zudot_rr"};
  return names;
}

const std::vector<std::string>& FullCarModel::parameterNames() const {
  return fullCarParameterNames();
}

const std::vector<std::string>& FullCarModel::channelNames() const {
  static const std::vector<std::string> names = {"u_fl", "u_fr", "u_rl", "u_rr",
                                                 "v_fl", "v_fr", "v_rl", "v_rr"};
  return names;
}

const std::vector<std::string>& FullCarModel::contactNames() {
  static const std::vector<std::string> names = {"front_left", "front_right", "rear_left",
                                                 "rear_right"};
  return names;
}

std::string FullCarModel::invalidReason(const Eigen::Ref<const Eigen::VectorXd>& params) const {
  const std::string why = fullCarParameterRuleViolation(params);
  if (!why.empty()) return why;
  try {
    solveFullCarEquilibrium(FullCarParameters::fromVector(params, nominal_));
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

std::unique_ptr<ModelBatch> FullCarModel::prepare(const Eigen::MatrixXd& params) const {
  if (params.rows() != nominal_vector_.size()) {
    throw std::invalid_argument("FullCarModel::prepare: expected " +
                                std::to_string(nominal_vector_.size()) + " parameter rows");
  }
  const double scale = nominal_.damper == DamperLaw::kTanh ? nominal_.damper_tanh_scale : 1.0;
  std::vector<PointConstants> points;
  points.reserve(params.cols());
  for (Eigen::Index q = 0; q < params.cols(); ++q) {
    const std::string prefix = "FullCarModel::prepare: column " + std::to_string(q) + ": ";
    const std::string why = fullCarParameterRuleViolation(params.col(q));
    if (!why.empty()) throw std::invalid_argument(prefix + why);
    const FullCarParameters p = FullCarParameters::fromVector(params.col(q), nominal_);
    FullCarEquilibrium e;
    try {
      e = solveFullCarEquilibrium(p);
    } catch (const std::runtime_error& error) {
      throw std::invalid_argument(prefix + error.what());
    }
    points.push_back(constantsOf(p, e, scale));
  }
  return std::make_unique<FullCarBatch>(std::move(points), nominal_.damper,
                                        nominal_.damper_tanh_rate, road_);
}

std::vector<double> FullCarModel::breakpoints(double t0, double t1) const {
  return road_->breakpoints(t0, t1);
}

}  // namespace pc_ekf
