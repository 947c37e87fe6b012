#include "pc_ekf/io/vehicle_section.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "pc_ekf/io/yaml_reader.h"
#include "pc_ekf/model/suspension_laws.h"

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

constexpr double kInf = std::numeric_limits<double>::infinity();

// Whether the model has parameter `name`.
bool hasParameter(const ModelDescription& d, const std::string& name) {
  const auto& names = d.parameters().names();
  return std::find(names.begin(), names.end(), name) != names.end();
}

// The sides of a model's suspensions: X of every spring_linear_X (left and
// right; front and rear).
std::vector<std::string> springSides(const ModelDescription& d) {
  std::vector<std::string> sides;
  const std::string prefix = "spring_linear_";
  for (const std::string& n : d.parameters().names()) {
    if (n.compare(0, prefix.size(), prefix) == 0) sides.push_back(n.substr(prefix.size()));
  }
  return sides;
}

// A datasheet number (absent: NaN), > 0 (or >= 0).
double optionalNumber(YamlMapReader& r, const std::string& key, bool zero_allowed = false) {
  double v = std::numeric_limits<double>::quiet_NaN();
  r.number(key, v, 0.0, kInf, !zero_allowed);
  return v;
}

// Two keys for one value.
void refuseBoth(YamlMapReader& r, const std::string& given, const std::string& other,
                const std::string& why) {
  if (r.has(given) && r.has(other)) {
    r.fail(given, "given with " + other, "one of " + given + " and " + other + " (" + why + ")");
  }
}

// damper_table[_X]: {bump: [[v, F], ...], rebound: [[v, F], ...]} at the
// damper, velocities and forces as positive magnitudes; returns the curve at
// the wheel (velocity / ratio, force x ratio; extension positive) as a 2 x n
// matrix through (0, 0), checked by DamperCurve.
Eigen::MatrixXd readDamperTable(YamlMapReader& r, const std::string& key, double ratio) {
  YamlMapReader t = r.map(key);
  std::vector<std::pair<double, double>> points{{0.0, 0.0}};
  for (const char* branch : {"bump", "rebound"}) {
    const YAML::Node seq = t.sequence(branch);
    if (!seq.IsDefined() || seq.IsNull() || seq.size() == 0) {
      t.fail(branch, "(none)", "a list of [velocity m/s, force N] pairs, both >= 0");
    }
    const double sign = std::string(branch) == "bump" ? -1.0 : 1.0;
    std::vector<std::pair<double, double>> own;
    for (std::size_t j = 0; j < seq.size(); ++j) {
      const YAML::Node pair = seq[j];
      const std::string item = std::string(branch) + "[" + std::to_string(j) + "]";
      std::string text = yamlValueText(pair);
      if (pair.IsSequence() && pair.size() == 2) {
        text = "[" + (pair[0].IsScalar() ? pair[0].Scalar() : yamlValueText(pair[0])) + ", " +
               (pair[1].IsScalar() ? pair[1].Scalar() : yamlValueText(pair[1])) + "]";
      }
      double v = -1.0, f = -1.0;
      const bool ok = pair.IsSequence() && pair.size() == 2 && pair[0].IsScalar() &&
                      pair[1].IsScalar();
      try {
        if (ok) {
          v = pair[0].as<double>();
          f = pair[1].as<double>();
        }
      } catch (const YAML::Exception&) {
        v = f = -1.0;
      }
      if (!ok || !std::isfinite(v) || !std::isfinite(f) || v < 0.0 || f < 0.0) {
        t.fail(item, text, "[velocity m/s, force N], both finite and >= 0");
      }
      if (!own.empty() && !(v > own.back().first)) {
        t.fail(item, text, "velocities increasing along the list");
      }
      if (!own.empty() && f < own.back().second) {
        t.fail(item, text,
               "a monotone table: the force may not fall as the velocity rises");
      }
      own.push_back({v, f});
      if (v == 0.0 && f != 0.0) {
        t.fail(item, text, "a table through (0, 0): force 0 at velocity 0");
      }
      // At the wheel, extension positive.
      if (v > 0.0) points.push_back({sign * v / ratio, sign * f * ratio});
    }
    if (own.back().first == 0.0) t.fail(branch, yamlValueText(seq), "a point with velocity > 0");
  }
  t.finish();
  std::sort(points.begin(), points.end());
  Eigen::MatrixXd m(2, static_cast<Eigen::Index>(points.size()));
  for (std::size_t j = 0; j < points.size(); ++j) {
    m(0, static_cast<Eigen::Index>(j)) = points[j].first;
    m(1, static_cast<Eigen::Index>(j)) = points[j].second;
  }
  try {
    DamperCurve check(m, r.keyPath(key));
  } catch (const std::invalid_argument& e) {
    r.fail(key, "{...}", e.what());
  }
  return m;
}

// The datasheet forms read before the table (docs/models.md "Datasheet
// values"): the tracks and axle load share, which bound other entries.
void readGeometryForms(YamlMapReader& r, const ModelDescription& d, ModelParameters& out) {
  const ParameterTable& table = d.parameters();
  if (hasParameter(d, "bar_length")) {
    refuseBoth(r, "wheel_track", "spring_track", "the track once");
    refuseBoth(r, "wheel_track", "bar_length", "bar_length is the wheel track");
    refuseBoth(r, "spring_track", "bar_length", "bar_length is the wheel track");
    const double wheel = optionalNumber(r, "wheel_track");
    const double spring = optionalNumber(r, "spring_track");
    if (!std::isnan(wheel)) out.values[table.at("bar_length")] = wheel;
    if (!std::isnan(spring)) {
      // The arms' lever: spring track = motion ratio x wheel track.
      double ratio = 0.0;
      for (const char* side : {"left", "right"}) {
        double mr = optionalNumber(r, std::string("motion_ratio_") + side);
        if (std::isnan(mr)) {
          r.fail("spring_track", std::to_string(spring),
                 std::string("motion_ratio_left and motion_ratio_right with it (wheel track = "
                             "spring track / motion ratio); or give wheel_track"));
        }
        ratio += 0.5 * mr;
      }
      out.values[table.at("bar_length")] = spring / ratio;
    }
  }
  if (hasParameter(d, "front_axle_distance") && hasParameter(d, "rear_axle_distance")) {
    for (const char* direct : {"front_axle_distance", "rear_axle_distance"}) {
      refuseBoth(r, "wheelbase", direct, "a and b follow from the wheelbase and the load share");
      refuseBoth(r, "front_axle_load_share", direct,
                 "a and b follow from the wheelbase and the load share");
    }
    const double wheelbase = optionalNumber(r, "wheelbase");
    double share = std::numeric_limits<double>::quiet_NaN();
    r.number("front_axle_load_share", share, 0.0, 1.0, true);
    if (std::isnan(wheelbase) != std::isnan(share)) {
      r.fail(std::isnan(wheelbase) ? "front_axle_load_share" : "wheelbase", "given alone",
             "wheelbase and front_axle_load_share together");
    }
    if (share == 1.0) r.fail("front_axle_load_share", "1", "(0, 1)");
    if (!std::isnan(wheelbase)) {
      // The body's centre O: b / (a + b) of its weight on the front axle.
      out.values[table.at("front_axle_distance")] = (1.0 - share) * wheelbase;
      out.values[table.at("rear_axle_distance")] = share * wheelbase;
    }
  }
}

// Rates at the spring and damper with motion ratios, and the measured damper
// table, converted to the model's wheel values (after the table, so a
// conflicting direct key is named).
void readRateForms(YamlMapReader& r, const ModelDescription& d, ModelParameters& out) {
  const ParameterTable& table = d.parameters();
  const bool has_table_law = d.choiceIndex("damper") >= 0 &&
                             [&] {
                               const auto& o = d.choices()[d.choiceIndex("damper")].options;
                               return std::find(o.begin(), o.end(), "table") != o.end();
                             }();
  const bool shared_table = r.has("damper_table");
  bool any_table = false;
  for (const std::string& side : springSides(d)) {
    const std::string mr_key = "motion_ratio_" + side, dmr_key = "damper_motion_ratio_" + side;
    const std::string spring = "spring_rate_" + side, cubic = "spring_cubic_rate_" + side,
                      damper = "damper_rate_" + side, own_table = "damper_table_" + side;
    const std::string linear_key = "spring_linear_" + side, cubic_key = "spring_cubic_" + side,
                      damping_key = "damping_" + side;
    refuseBoth(r, spring, linear_key, linear_key + " is the wheel rate");
    refuseBoth(r, cubic, cubic_key, cubic_key + " is the wheel's cubic rate");
    refuseBoth(r, damper, damping_key, damping_key + " is the wheel's damping");
    refuseBoth(r, damper, own_table, "a rate or a table");
    refuseBoth(r, own_table, "damper_table", "one table per side");
    if (shared_table) refuseBoth(r, damper, "damper_table", "a rate or a table");
    const double ratio = optionalNumber(r, mr_key);
    double damper_ratio = optionalNumber(r, dmr_key);
    if (std::isnan(damper_ratio)) damper_ratio = std::isnan(ratio) ? 1.0 : ratio;
    const double k = optionalNumber(r, spring), k3 = optionalNumber(r, cubic, true),
                 c = optionalNumber(r, damper, true);
    const bool has_table = r.has(own_table) || shared_table;
    if (!std::isnan(ratio) && std::isnan(k) && std::isnan(k3) && std::isnan(c) && !has_table &&
        !r.has("spring_track")) {
      r.fail(mr_key, std::to_string(ratio),
             spring + ", " + damper + ", a damper table or spring_track with it (it converts "
             "datasheet values; the model's own keys are at the wheel)");
    }
    const double mr = std::isnan(ratio) ? 1.0 : ratio;
    if ((!std::isnan(k) || !std::isnan(k3)) && std::isnan(ratio)) {
      r.fail(std::isnan(k) ? cubic : spring, "without " + mr_key,
             mr_key + " (spring travel per wheel travel) with it");
    }
    if ((!std::isnan(c) || has_table) && std::isnan(ratio) && !r.has(dmr_key)) {
      r.fail(!std::isnan(c) ? damper : (r.has(own_table) ? own_table : "damper_table"),
             "without " + mr_key, mr_key + " or " + dmr_key + " (damper travel per wheel travel)");
    }
    // Wheel rate = rate x ratio^2 (force and travel both through the lever);
    // the cubic term x ratio^4.
    if (!std::isnan(k)) out.values[table.at(linear_key)] = k * mr * mr;
    if (!std::isnan(k3)) out.values[table.at(cubic_key)] = k3 * mr * mr * mr * mr;
    if (!std::isnan(c)) out.values[table.at(damping_key)] = c * damper_ratio * damper_ratio;
    if (!has_table) continue;
    if (!has_table_law) {
      r.fail(r.has(own_table) ? own_table : "damper_table", "{...}",
             "no damper table: this model's damper laws are " + [&] {
               std::string o;
               for (const auto& x : d.choices()[d.choiceIndex("damper")].options) {
                 o += (o.empty() ? "" : " or ") + x;
               }
               return o;
             }());
    }
    any_table = true;
    const Eigen::MatrixXd wheel =
        readDamperTable(r, r.has(own_table) ? own_table : "damper_table", damper_ratio);
    out.tables["damper_table_" + side] = wheel;
    // The table as measured is damping = its slope at 0; a configured
    // damping_X scales it.
    if (!r.has(damping_key)) {
      out.values[table.at(damping_key)] = DamperCurve(wheel, damping_key).referenceDamping();
    }
  }
  if (any_table) {
    const int c = d.choiceIndex("damper");
    std::string law = "table";
    r.text("damper", law);
    if (law != "table") {
      r.fail("damper", law, "table (a damper table is given) or no damper table");
    }
    out.choices[static_cast<std::size_t>(c)] = law;
  }
}

}  // namespace

std::shared_ptr<ModelParameters> readVehicleSection(YamlMapReader& r, const ModelDescription& d,
                                                    const ModelParameters& base) {
  auto out = std::make_shared<ModelParameters>(base);
  readGeometryForms(r, d, *out);
  readTable(r, d.parameters(), out->values);
  readRateForms(r, d, *out);
  if (hasParameter(d, "body_cg_offset") && hasParameter(d, "bar_length")) {
    const double offset = out->values[d.parameters().at("body_cg_offset")];
    const double half = 0.5 * out->values[d.parameters().at("bar_length")];
    if (!(std::abs(offset) <= half)) {
      r.fail("body_cg_offset", std::to_string(offset),
             "[-" + std::to_string(half) + ", " + std::to_string(half) +
                 "] (half the bar_length: the body's centre between the mounts)");
    }
  }
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
    if (spec.name == "damper" && value == "table") {
      for (const std::string& side : springSides(d)) {
        if (!out->tables.count("damper_table_" + side)) {
          r.fail("damper", "table", "damper_table (or damper_table_" + side +
                                        ") with it: the measured curve");
        }
      }
    }
    if (spec.name == "damper" && value != "table") {
      for (const std::string& side : springSides(d)) out->tables.erase("damper_table_" + side);
    }
  }
  readTable(r, d.settings(), out->settings);
  return out;
}

}  // namespace pc_ekf
