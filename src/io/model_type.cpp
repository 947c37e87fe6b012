// The `vehicle:` section of any model, read from its description's tables.
#include "pc_ekf/io/model_type.h"

#include <cmath>
#include <stdexcept>

#include "pc_ekf/io/yaml_reader.h"

namespace pc_ekf {

namespace {

// Entries without a bound from other entries first, then those bounded by
// others (so the bound is the configured value, e.g. bar_length).
void readTable(YamlMapReader& r, const ParameterTable& table, Eigen::VectorXd& values) {
  for (const bool relative : {false, true}) {
    for (int i = 0; i < table.size(); ++i) {
      const ParameterDomain& d = table[i].domain;
      if (d.upper_sum.empty() == relative) continue;
      const bool config = !std::isnan(d.config_lower);
      r.number(table[i].name, values[i], config ? d.config_lower : d.lower,
               table.upperBound(i, values), !config && !d.zero_allowed);
    }
  }
}

}  // namespace

namespace {

// The left track of a speed bump under a model's single contact.
class OneContactBump : public ContactRoad {
 public:
  explicit OneContactBump(const SpeedBumpSettings& s) : bump_(s) {}
  int contactCount() const override { return 1; }
  void heights(double t, Eigen::Ref<Eigen::VectorXd> out) const override {
    out[0] = bump_.height(t)[0];
  }
  std::vector<double> breakpoints(double t0, double t1) const override {
    return bump_.breakpoints(t0, t1);
  }

 private:
  SpeedBumpRoad bump_;
};

}  // namespace

std::shared_ptr<const ContactRoad> ModelType::speedBump(const SpeedBumpSettings& s,
                                                        const ModelParameters&) const {
  switch (contactNames().size()) {
    case 1:
      return std::make_shared<OneContactBump>(s);
    case 2:
      return std::make_shared<SpeedBumpRoad>(s);
    default:
      throw std::invalid_argument(name() + ": no speed bump for " +
                                  std::to_string(contactNames().size()) + " contacts");
  }
}

std::shared_ptr<const MechanicalModel> ModelType::build(const ModelParameters& parameters,
                                                        std::shared_ptr<const ContactRoad> road,
                                                        const ReadingSettings& readings) const {
  if (readings.as_states || readings.zero != ZeroConvention::kRest) {
    throw std::invalid_argument(name() + ": reads its channels as deviations from rest only " +
                                "(no IMU channels, no measurement.zero: tare)");
  }
  return build(parameters, std::move(road));
}

std::shared_ptr<const MechanicalModel> ModelType::buildRoadFree(
    const ModelParameters&, std::shared_ptr<const ReadingInputs>, ZeroConvention) const {
  throw std::invalid_argument("model " + name() + " has no road-free form (road.source: none)");
}

std::shared_ptr<const ContactRoad> ModelType::drivenProfile(
    std::shared_ptr<const TrackProfile> profile, double speed, const ModelParameters&) const {
  switch (contactNames().size()) {
    case 1:
      return std::make_shared<DrivenProfileRoad>(std::move(profile), speed,
                                                 std::vector<std::pair<int, double>>{{0, 0.0}});
    case 2:
      return std::make_shared<DrivenProfileRoad>(
          std::move(profile), speed, std::vector<std::pair<int, double>>{{0, 0.0}, {1, 0.0}});
    default:
      throw std::invalid_argument(name() + ": no road by distance for " +
                                  std::to_string(contactNames().size()) + " contacts");
  }
}

std::shared_ptr<ModelParameters> ModelType::defaults() const {
  return std::make_shared<ModelParameters>(ModelParameters::defaults(description()));
}

std::shared_ptr<ModelParameters> ModelType::read(YamlMapReader& r,
                                                 const ModelParameters& base) const {
  const ModelDescription& d = description();
  auto out = std::make_shared<ModelParameters>(base);
  readTable(r, d.parameters(), out->values);
  // An entry that follows another (e.g. midway between the mounts) keeps
  // following it when it is not configured and still followed it in `base`.
  const ParameterTable& table = d.parameters();
  for (int i = 0; i < table.size(); ++i) {
    const ParameterSpec& spec = table[i];
    if (spec.default_fraction_of.empty() || r.has(spec.name)) continue;
    const int of = table.at(spec.default_fraction_of);
    if (base.values[i] == spec.default_fraction * base.values[of]) {
      out->values[i] = spec.default_fraction * out->values[of];
    }
  }
  for (std::size_t c = 0; c < d.choices().size(); ++c) {
    const ChoiceSpec& spec = d.choices()[c];
    std::string& value = out->choices[c];
    r.text(spec.name, value);
    bool known = false;
    std::string options;
    for (const auto& o : spec.options) {
      known |= o == value;
      options += (options.empty() ? "" : " or ") + o;
    }
    if (!known) r.fail(spec.name, "'" + value + "'", options);
  }
  readTable(r, d.settings(), out->settings);
  return out;
}

}  // namespace pc_ekf
