#include "pc_ekf/io/vehicle_file.h"

#include <yaml-cpp/yaml.h>

#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "pc_ekf/io/yaml_reader.h"

namespace pc_ekf {

void anchorVehicleFile(YAML::Node& root, const std::string& config_path) {
  if (!root.IsMap() || !root["vehicle_file"] || !root["vehicle_file"].IsScalar()) return;
  const std::filesystem::path file = root["vehicle_file"].Scalar();
  if (file.empty() || file.is_absolute()) return;
  const std::filesystem::path dir = std::filesystem::path(config_path).parent_path();
  root["vehicle_file"] = (dir / file).lexically_normal().string();
}

namespace {

// The datasheet forms (docs/models.md) that set a model key: a vehicle file's
// value of that key replaces them too (calibrate_vehicle writes model keys).
std::vector<std::string> datasheetFormsOf(const std::string& key) {
  const auto side = [&](const std::string& prefix) {
    return key.compare(0, prefix.size(), prefix) == 0 ? key.substr(prefix.size()) : "";
  };
  if (!side("spring_linear_").empty()) return {"spring_rate_" + side("spring_linear_")};
  if (!side("spring_cubic_").empty()) return {"spring_cubic_rate_" + side("spring_cubic_")};
  if (!side("damping_").empty()) return {"damper_rate_" + side("damping_")};
  if (key == "bar_length") return {"wheel_track", "spring_track"};
  return {};
}

// Motion ratios left with nothing to convert (their rates replaced above).
void dropUnusedMotionRatios(YAML::Node& vehicle) {
  const YAML::Node look = vehicle;  // const lookups add no keys
  std::vector<std::string> unused;
  for (const auto& entry : look) {
    const std::string k = entry.first.Scalar();
    for (const std::string prefix : {"motion_ratio_", "damper_motion_ratio_"}) {
      if (k.compare(0, prefix.size(), prefix) != 0) continue;
      const std::string side = k.substr(prefix.size());
      bool used = look["damper_table"] || look["spring_track"];
      for (const std::string rate :
           {"spring_rate_", "spring_cubic_rate_", "damper_rate_", "damper_table_"}) {
        used = used || look[rate + side];
      }
      if (!used) unused.push_back(k);
    }
  }
  for (const std::string& k : unused) vehicle.remove(k);
}

}  // namespace

YAML::Node mergeVehicleFile(const YAML::Node& root, const std::string& source, std::string* path) {
  if (path) path->clear();
  if (!root.IsMap() || !root["vehicle_file"]) return root;
  const YAML::Node key = root["vehicle_file"];
  if (!key.IsScalar() || key.Scalar().empty()) {
    throw ConfigError(source + ": key 'vehicle_file': expected the path of a vehicle file "
                      "(calibrate_vehicle's output), got " + yamlValueText(key));
  }
  const std::string file = key.Scalar();
  YAML::Node vf;
  try {
    vf = YAML::LoadFile(file);
  } catch (const YAML::BadFile&) {
    throw ConfigError(source + ": key 'vehicle_file': cannot open '" + file +
                      "' (a relative path is relative to the config file)");
  } catch (const YAML::Exception& e) {
    throw ConfigError(file + ": line " + std::to_string(e.mark.line + 1) +
                      ": not valid YAML (" + e.msg + ") (vehicle_file of " + source + ")");
  }
  if (!vf.IsMap()) {
    throw ConfigError(file + ": a vehicle file is a map with vehicle: and tolerances: (vehicle_file of " +
                      source + ")");
  }
  YAML::Node out = YAML::Clone(root);
  out.remove("vehicle_file");
  for (const auto& kv : vf) {
    const std::string section = kv.first.IsScalar() ? kv.first.Scalar() : "";
    if (section != "vehicle" && section != "tolerances") {
      throw ConfigError(file + ": key '" + (section.empty() ? yamlValueText(kv.first) : section) +
                        "': a vehicle file holds only vehicle: and tolerances: (vehicle_file of " +
                        source + ")");
    }
    if (kv.second.IsNull()) continue;
    if (!kv.second.IsMap()) {
      throw ConfigError(file + ": key '" + section + "': expected a map, got " +
                        yamlValueText(kv.second));
    }
    if (!out[section] || out[section].IsNull()) out[section] = YAML::Node(YAML::NodeType::Map);
    YAML::Node target = out[section];
    if (!target.IsMap()) continue;  // the config's own wrong type is reported by the parser
    for (const auto& entry : kv.second) {
      target[entry.first.Scalar()] = YAML::Clone(entry.second);
      if (section != "vehicle") continue;
      for (const std::string& form : datasheetFormsOf(entry.first.Scalar())) target.remove(form);
    }
    if (section == "vehicle") dropUnusedMotionRatios(target);
  }
  if (path) *path = file;
  return out;
}

std::string vehicleFileText(const VehicleFile& f) {
  std::ostringstream out;
  for (const auto& line : f.header) out << "#" << (line.empty() ? "" : " ") << line << "\n";
  out << "vehicle:\n";
  for (const auto& [key, value] : f.vehicle) out << "  " << key << ": " << value << "\n";
  out << "tolerances:                     # value = nominal (1 + relative_range xi)\n";
  if (f.tolerances.empty()) out << "  {}\n";
  for (const auto& u : f.tolerances) {
    out << "  " << u.name << ": {";
    std::string vehicle_value;
    for (const auto& [key, value] : f.vehicle) {
      if (key == u.name) vehicle_value = value;
    }
    if (vehicle_value.empty() || std::strtod(vehicle_value.c_str(), nullptr) != u.nominal) {
      out << "nominal: " << roundTripText(u.nominal) << ", ";
    }
    out << "relative_range: " << roundTripText(u.relative_range);
    const GermSpec beta22;
    if (u.germ.family != beta22.family || u.germ.alpha != beta22.alpha || u.germ.beta != beta22.beta) {
      out << ", germ: {family: " << toString(u.germ.family);
      if (u.germ.family == GermFamily::kBeta || u.germ.family == GermFamily::kGamma) {
        out << ", alpha: " << roundTripText(u.germ.alpha);
      }
      if (u.germ.family == GermFamily::kBeta) out << ", beta: " << roundTripText(u.germ.beta);
      out << "}";
    }
    out << "}\n";
  }
  return out.str();
}

}  // namespace pc_ekf
