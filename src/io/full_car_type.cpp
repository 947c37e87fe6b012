// The 7-DOF full car as a model type: `vehicle:` keys are the
// FullCarParameters names plus the damper law; four contacts, eight channels,
// one suspension joint per corner.
#include <limits>

#include "pc_ekf/io/model_type.h"
#include "pc_ekf/io/yaml_reader.h"
#include "pc_ekf/model/full_car_model.h"
#include "pc_ekf/model/full_car_road.h"

namespace pc_ekf {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct FullCarSettings : ModelParameters {
  FullCarParameters car;
};

class FullCarType : public ModelType {
 public:
  std::string name() const override { return "full_car"; }
  const std::vector<std::string>& parameterNames() const override { return fullCarParameterNames(); }
  const std::vector<std::string>& contactNames() const override {
    return FullCarModel::contactNames();
  }
  const std::vector<std::string>& channelNames() const override {
    static const std::vector<std::string> c{"u_fl", "u_fr", "u_rl", "u_rr",
                                            "v_fl", "v_fr", "v_rl", "v_rr"};
    return c;
  }
  const std::vector<SuspensionJoint>& suspensions() const override {
    static const std::vector<SuspensionJoint> s{
        {"front_left_suspension", "front_left", 0, 4},
        {"front_right_suspension", "front_right", 1, 5},
        {"rear_left_suspension", "rear_left", 2, 6},
        {"rear_right_suspension", "rear_right", 3, 7}};
    return s;
  }
  std::shared_ptr<ModelParameters> defaults() const override {
    auto p = std::make_shared<FullCarSettings>();
    p->values = p->car.toVector();
    return p;
  }
  std::shared_ptr<ModelParameters> read(YamlMapReader& r, const ModelParameters& base) const override {
    auto out = std::make_shared<FullCarSettings>(dynamic_cast<const FullCarSettings&>(base));
    FullCarParameters& car = out->car;
    car = FullCarParameters::fromVector(base.values, car);
    Eigen::VectorXd p = car.toVector();
    const auto& names = fullCarParameterNames();
    for (std::size_t i = 0; i < names.size(); ++i) {
      const std::string& n = names[i];
      const bool may_be_zero = n.rfind("spring_cubic", 0) == 0 || n.rfind("damping", 0) == 0 ||
                               n == "added_mass" || n == "added_mass_x" || n == "added_mass_y";
      r.number(n, p[i], 0.0, kInf, !may_be_zero);
    }
    std::string damper = car.damper == DamperLaw::kTanh ? "tanh" : "linear";
    r.text("damper", damper);
    if (damper != "tanh" && damper != "linear") r.fail("damper", "'" + damper + "'", "tanh or linear");
    car = FullCarParameters::fromVector(p, car);
    car.damper = damper == "tanh" ? DamperLaw::kTanh : DamperLaw::kLinear;
    r.number("damper_tanh_scale", car.damper_tanh_scale, 0.0, kInf, true);
    r.number("damper_tanh_rate", car.damper_tanh_rate, 0.0, kInf, true);
    const std::string why = fullCarParameterRuleViolation(p);
    if (!why.empty()) r.fail("added_mass", "(vehicle)", "a physical full car: " + why);
    out->values = p;
    return out;
  }
  std::shared_ptr<const MechanicalModel> build(const ModelParameters& p,
                                               std::shared_ptr<const ContactRoad> road) const override {
    return std::make_shared<FullCarModel>(laws(p), std::move(road));
  }
  std::shared_ptr<const ContactRoad> speedBump(const SpeedBumpSettings& s,
                                               const ModelParameters& p) const override {
    FullCarBumpSettings b;
    b.speed_kmh = s.speed_kmh;
    b.height_left = s.height_left;
    b.height_right = s.height_right;
    b.ramp_up_length = s.ramp_up_length;
    b.flat_length = s.flat_length;
    b.ramp_down_length = s.ramp_down_length;
    // The right wheels meet the bump delay_fraction of its length later (an
    // oblique bump: 0.6 m at the default 3 m bump and 0.2).
    b.right_offset = s.delay_fraction * (s.ramp_up_length + s.flat_length + s.ramp_down_length);
    b.wheelbase = laws(p).wheelbase();
    if (s.start_distance != 0.0) {
      throw std::invalid_argument("full_car speed bump: road.speed_bump.start_distance must be 0");
    }
    return std::make_shared<FullCarBumpRoad>(b);
  }

  static FullCarParameters laws(const ModelParameters& p) {
    return FullCarParameters::fromVector(p.values, dynamic_cast<const FullCarSettings&>(p).car);
  }
};

}  // namespace

std::shared_ptr<const ModelType> fullCarType() {
  static const auto type = std::make_shared<const FullCarType>();
  return type;
}

}  // namespace pc_ekf
