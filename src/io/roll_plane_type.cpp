// The paper's roll-plane bar as a model type: `vehicle:` keys are the
// VehicleParameters names plus the damper law.
#include <algorithm>
#include <limits>

#include "pc_ekf/io/model_type.h"
#include "pc_ekf/io/yaml_reader.h"
#include "pc_ekf/model/roll_plane_model.h"

namespace pc_ekf {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct RollPlaneParameters : ModelParameters {
  VehicleParameters vehicle;
};

class RollPlaneType : public ModelType {
 public:
  std::string name() const override { return "roll_plane"; }
  const std::vector<std::string>& parameterNames() const override { return vehicleParameterNames(); }
  const std::vector<std::string>& contactNames() const override {
    static const std::vector<std::string> c{"left", "right"};
    return c;
  }
  std::vector<std::string> roadColumns() const override { return {"y1", "y2"}; }
  const std::vector<std::string>& channelNames() const override {
    static const std::vector<std::string> c{"u1", "u2", "v1", "v2"};
    return c;
  }
  const std::vector<SuspensionJoint>& suspensions() const override {
    static const std::vector<SuspensionJoint> s{{"left_suspension", "left", 0, 2},
                                                {"right_suspension", "right", 1, 3}};
    return s;
  }
  std::shared_ptr<ModelParameters> defaults() const override {
    auto p = std::make_shared<RollPlaneParameters>();
    p->values = p->vehicle.toVector();
    return p;
  }
  std::shared_ptr<ModelParameters> read(YamlMapReader& r, const ModelParameters& base) const override;
  std::shared_ptr<const MechanicalModel> build(const ModelParameters& p,
                                               std::shared_ptr<const ContactRoad> road) const override {
    return std::make_shared<RollPlaneModel>(laws(p), std::move(road));
  }
  std::shared_ptr<const ContactRoad> speedBump(const SpeedBumpSettings& s,
                                               const ModelParameters&) const override {
    return std::make_shared<SpeedBumpRoad>(s);
  }

  static VehicleParameters laws(const ModelParameters& p) {
    const auto& r = dynamic_cast<const RollPlaneParameters&>(p);
    return VehicleParameters::fromVector(p.values, r.vehicle);
  }
};

std::shared_ptr<ModelParameters> RollPlaneType::read(YamlMapReader& r,
                                                     const ModelParameters& base) const {
  auto out = std::make_shared<RollPlaneParameters>(dynamic_cast<const RollPlaneParameters&>(base));
  VehicleParameters& v = out->vehicle;
  v = laws(base);
  Eigen::VectorXd p = v.toVector();
  const auto& names = vehicleParameterNames();
  for (std::size_t i = 0; i < names.size(); ++i) {
    const std::string& n = names[i];
    if (n == "damping_left" || n == "damping_right" || n == "spring_cubic_left" ||
        n == "spring_cubic_right" || n == "added_mass") {
      r.number(n, p[i], 0.0, kInf);
    } else if (n != "added_mass_position") {
      r.number(n, p[i], 0.0, kInf, true);
    }
  }
  const auto index = [&](const char* key) {
    return static_cast<int>(std::find(names.begin(), names.end(), key) - names.begin());
  };
  r.number("added_mass_position", p[index("added_mass_position")], 0.0, p[index("bar_length")]);
  std::string damper = v.damper == DamperLaw::kTanh ? "tanh" : "linear";
  r.text("damper", damper);
  if (damper != "tanh" && damper != "linear") r.fail("damper", "'" + damper + "'", "tanh or linear");
  v = VehicleParameters::fromVector(p, v);
  v.damper = damper == "tanh" ? DamperLaw::kTanh : DamperLaw::kLinear;
  r.number("damper_tanh_scale", v.damper_tanh_scale, 0.0, kInf, true);
  r.number("damper_tanh_rate", v.damper_tanh_rate, 0.0, kInf, true);
  out->values = v.toVector();
  return out;
}

}  // namespace

std::shared_ptr<const ModelType> rollPlaneType() {
  static const auto type = std::make_shared<const RollPlaneType>();
  return type;
}

VehicleParameters rollPlaneVehicle(const ModelParameters& p) { return RollPlaneType::laws(p); }

std::shared_ptr<ModelParameters> rollPlaneParameters(const VehicleParameters& v) {
  auto p = std::make_shared<RollPlaneParameters>();
  p->vehicle = v;
  p->values = v.toVector();
  return p;
}

}  // namespace pc_ekf
