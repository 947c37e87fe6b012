#include "pc_ekf/ros/ros_config.h"

#include <ros/param.h>

#include <fstream>
#include <sstream>

#include "pc_ekf/io/checkpoint.h"
#include "pc_ekf/io/number_text.h"
#include "pc_ekf/io/vehicle_file.h"
#include "pc_ekf/ros/model_plugins.h"

namespace pc_ekf {
namespace {

YAML::Node loadYamlFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot open the configuration file (param ~config_file)");
  std::stringstream text;
  text << in.rdbuf();
  try {
    return YAML::Load(text.str());
  } catch (const YAML::Exception& e) {
    throw ConfigError(path + ": line " + std::to_string(e.mark.line + 1) + ": not valid YAML (" +
                      e.msg + ")");
  }
}

}  // namespace

YAML::Node yamlFromXmlRpc(const XmlRpc::XmlRpcValue& value) {
  XmlRpc::XmlRpcValue v = value;  // the accessors are non-const
  switch (v.getType()) {
    case XmlRpc::XmlRpcValue::TypeBoolean:
      return YAML::Node(static_cast<bool>(v) ? "true" : "false");
    case XmlRpc::XmlRpcValue::TypeInt:
      return YAML::Node(std::to_string(static_cast<int>(v)));
    case XmlRpc::XmlRpcValue::TypeDouble:
      return YAML::Node(roundTripText(static_cast<double>(v)));  // reads back bit for bit
    case XmlRpc::XmlRpcValue::TypeString:
      return YAML::Node(static_cast<std::string>(v));
    case XmlRpc::XmlRpcValue::TypeArray: {
      YAML::Node seq(YAML::NodeType::Sequence);
      for (int i = 0; i < v.size(); ++i) seq.push_back(yamlFromXmlRpc(v[i]));
      return seq;
    }
    case XmlRpc::XmlRpcValue::TypeStruct: {
      YAML::Node map(YAML::NodeType::Map);
      for (auto it = v.begin(); it != v.end(); ++it) map[it->first] = yamlFromXmlRpc(it->second);
      return map;
    }
    default:
      return YAML::Node(v.toXml());  // date/binary: refused by the schema as text
  }
}

void mergeYaml(YAML::Node& base, const YAML::Node& overlay) {
  if (!base.IsMap() || !overlay.IsMap()) {
    base = overlay;
    return;
  }
  for (const auto& kv : overlay) {
    const std::string key = kv.first.as<std::string>();
    if (base[key].IsMap() && kv.second.IsMap()) {
      YAML::Node child = base[key];
      mergeYaml(child, kv.second);
    } else {
      base[key] = YAML::Clone(kv.second);
    }
  }
}

EstimatorConfig loadRosConfig(const ros::NodeHandle& private_nh, std::uint64_t* config_hash,
                              StartSensitivity* start) {
  const std::string ns = private_nh.getNamespace();
  std::string file;
  private_nh.getParam(kConfigFileParam, file);

  YAML::Node params(YAML::NodeType::Map);
  XmlRpc::XmlRpcValue all;
  if (ros::param::get(ns, all) && all.getType() == XmlRpc::XmlRpcValue::TypeStruct) {
    for (auto it = all.begin(); it != all.end(); ++it) {
      if (it->first == kConfigFileParam || it->first == kDiagnosticPeriodParam ||
          it->first == kCheckpointFileParam || it->first == kCheckpointEveryParam) {
        continue;
      }
      params[it->first] = yamlFromXmlRpc(it->second);
    }
  }

  std::string source;
  YAML::Node root(YAML::NodeType::Map);
  if (!file.empty()) {
    root = loadYamlFile(file);
    if (root.IsNull()) root = YAML::Node(YAML::NodeType::Map);
    if (!root.IsMap()) return parseConfig(root, file, modelRegistryWithPlugins());  // reports the wrong root type
    source = file;
  }
  anchorVehicleFile(root, file);  // relative to the config file (or the working directory)
  if (params.size() > 0) {
    if (params["vehicle_file"]) anchorVehicleFile(params, "");
    mergeYaml(root, params);
    source = source.empty() ? "rosparam " + ns : source + " + rosparam " + ns;
  }
  if (source.empty()) source = "defaults (no ~config_file, no private parameters)";
  EstimatorConfig config = parseConfig(root, source, modelRegistryWithPlugins());
  // The identity covers the vehicle file's contents, not only its name.
  if (config_hash) *config_hash = fnv1a64(canonicalConfigText(mergeVehicleFile(root, source, nullptr)));
  if (start) *start = startSensitivity(config);
  return config;
}

}  // namespace pc_ekf
