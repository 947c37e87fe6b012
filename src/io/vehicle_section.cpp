#include "pc_ekf/io/vehicle_section.h"

#include <cmath>

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

std::shared_ptr<ModelParameters> readVehicleSection(YamlMapReader& r, const ModelDescription& d,
                                                    const ModelParameters& base) {
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
