// A mechanism pc_ekf does not know, estimated through its public model
// interface: the 2-DOF quarter car. A sprung mass m_s on a linear spring k and
// damper c over an unsprung mass m_u on a linear tyre k_t, riding one road
// contact y(t). Linear, so the deviations from the static equilibrium obey
//   m_s z_s'' = -k u - c v,   m_u z_u'' = k u + c v - k_t (z_u - y),
// with u = z_s - z_u (suspension extension) and v = u' (the two channels).
#include <pc_ekf/io/model_type.h>
#include <pc_ekf/io/yaml_reader.h>
#include <pc_ekf/model/road_input.h>
#include <pluginlib/class_list_macros.hpp>

#include <limits>
#include <sstream>
#include <stdexcept>

namespace pc_ekf_quarter_car {
namespace {

using pc_ekf::ContactRoad;
using pc_ekf::MechanicalModel;
using pc_ekf::ModelBatch;
using pc_ekf::ModelParameters;

const std::vector<std::string>& parameterNames() {
  static const std::vector<std::string> n{"sprung_mass", "unsprung_mass", "spring", "damping",
                                          "tyre_stiffness"};
  return n;
}

class QuarterCarBatch : public ModelBatch {
 public:
  QuarterCarBatch(const Eigen::MatrixXd& params, const ContactRoad& road)
      : p_(params), road_(road) {}
  int pointCount() const override { return static_cast<int>(p_.cols()); }
  Eigen::ArrayXXd initialState() const override { return Eigen::ArrayXXd::Zero(4, p_.cols()); }
  void derivatives(double t, const Eigen::ArrayXXd& y, Eigen::ArrayXXd& dydt) const override {
    Eigen::VectorXd h(1);
    road_.heights(t, h);
    for (Eigen::Index q = 0; q < p_.cols(); ++q) {
      const double ms = p_(0, q), mu = p_(1, q), k = p_(2, q), c = p_(3, q), kt = p_(4, q);
      const double u = y(0, q) - y(1, q), v = y(2, q) - y(3, q);
      const double f = -k * u - c * v;  // suspension force on the sprung mass
      dydt(0, q) = y(2, q);
      dydt(1, q) = y(3, q);
      dydt(2, q) = f / ms;
      dydt(3, q) = (-f - kt * (y(1, q) - h[0])) / mu;
    }
  }

 private:
  Eigen::MatrixXd p_;
  const ContactRoad& road_;
};

class QuarterCarModel : public MechanicalModel {
 public:
  QuarterCarModel(Eigen::VectorXd nominal, std::shared_ptr<const ContactRoad> road)
      : nominal_(std::move(nominal)), h_(Eigen::MatrixXd::Zero(2, 4)), road_(std::move(road)) {
    if (!road_ || road_->contactCount() != 1) {
      throw std::invalid_argument("quarter car: a road under one contact expected");
    }
    const std::string why = invalidReason(nominal_);
    if (!why.empty()) throw std::invalid_argument("quarter car: " + why);
    h_(0, 0) = 1.0;
    h_(0, 1) = -1.0;
    h_(1, 2) = 1.0;
    h_(1, 3) = -1.0;
  }
  int stateSize() const override { return 4; }
  const std::vector<std::string>& stateNames() const override {
    static const std::vector<std::string> n{"z_s", "z_u", "z_s_rate", "z_u_rate"};
    return n;
  }
  const std::vector<std::string>& parameterNames() const override {
    return pc_ekf_quarter_car::parameterNames();
  }
  const Eigen::VectorXd& nominalParameters() const override { return nominal_; }
  std::string invalidReason(const Eigen::Ref<const Eigen::VectorXd>& p) const override {
    const auto& names = parameterNames();
    if (p.size() != static_cast<Eigen::Index>(names.size())) return "wrong parameter count";
    for (Eigen::Index i = 0; i < p.size(); ++i) {
      const bool ok = names[i] == "damping" ? p[i] >= 0.0 : p[i] > 0.0;
      if (!ok || !std::isfinite(p[i])) {
        std::ostringstream o;
        o << names[i] << " = " << p[i] << (names[i] == "damping" ? " must be >= 0" : " must be > 0");
        return o.str();
      }
    }
    return "";
  }
  const std::vector<std::string>& channelNames() const override {
    static const std::vector<std::string> c{"u", "v"};
    return c;
  }
  const Eigen::MatrixXd& observationMatrix() const override { return h_; }
  std::unique_ptr<ModelBatch> prepare(const Eigen::MatrixXd& params) const override {
    return std::make_unique<QuarterCarBatch>(params, *road_);
  }
  std::vector<double> breakpoints(double t0, double t1) const override {
    return road_->breakpoints(t0, t1);
  }
  const ContactRoad* contactRoad() const override { return road_.get(); }

 private:
  Eigen::VectorXd nominal_;
  Eigen::MatrixXd h_;
  std::shared_ptr<const ContactRoad> road_;
};

// The config's speed bump under the one wheel (its left height).
class OneWheelBump : public ContactRoad {
 public:
  explicit OneWheelBump(const pc_ekf::SpeedBumpSettings& s) : bump_(s) {}
  int contactCount() const override { return 1; }
  void heights(double t, Eigen::Ref<Eigen::VectorXd> out) const override { out[0] = bump_.height(t)[0]; }
  std::vector<double> breakpoints(double t0, double t1) const override {
    return bump_.breakpoints(t0, t1);
  }

 private:
  pc_ekf::SpeedBumpRoad bump_;
};

}  // namespace

class QuarterCarType : public pc_ekf::ModelType {
 public:
  std::string name() const override { return "pc_ekf_quarter_car/QuarterCar"; }
  const std::vector<std::string>& parameterNames() const override {
    return pc_ekf_quarter_car::parameterNames();
  }
  const std::vector<std::string>& contactNames() const override {
    static const std::vector<std::string> c{"wheel"};
    return c;
  }
  const std::vector<std::string>& channelNames() const override {
    static const std::vector<std::string> c{"u", "v"};
    return c;
  }
  const std::vector<pc_ekf::SuspensionJoint>& suspensions() const override {
    static const std::vector<pc_ekf::SuspensionJoint> s{{"quarter_suspension", "wheel", 0, 1}};
    return s;
  }
  std::shared_ptr<ModelParameters> defaults() const override {
    auto p = std::make_shared<ModelParameters>();
    p->values.resize(5);
    p->values << 300.0, 40.0, 20000.0, 1500.0, 200000.0;
    return p;
  }
  std::shared_ptr<ModelParameters> read(pc_ekf::YamlMapReader& r,
                                        const ModelParameters& base) const override {
    auto out = std::make_shared<ModelParameters>(base);
    const auto& names = parameterNames();
    for (std::size_t i = 0; i < names.size(); ++i) {
      r.number(names[i], out->values[static_cast<Eigen::Index>(i)], 0.0,
               std::numeric_limits<double>::infinity(), names[i] != "damping");
    }
    return out;
  }
  std::shared_ptr<const MechanicalModel> build(const ModelParameters& p,
                                               std::shared_ptr<const ContactRoad> road) const override {
    return std::make_shared<QuarterCarModel>(p.values, std::move(road));
  }
  std::shared_ptr<const ContactRoad> speedBump(const pc_ekf::SpeedBumpSettings& s,
                                               const ModelParameters&) const override {
    return std::make_shared<OneWheelBump>(s);
  }
};

}  // namespace pc_ekf_quarter_car

PLUGINLIB_EXPORT_CLASS(pc_ekf_quarter_car::QuarterCarType, pc_ekf::ModelType)
