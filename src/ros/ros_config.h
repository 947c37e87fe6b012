// estimator_node configuration from the parameter server: the same YAML
// schema as the CLIs (config/speed_bump.yaml), read from the file named by
// ~config_file and/or the private namespace itself (`rosparam load FILE
// /estimator_node`). Private parameters override the file, maps merged key
// by key.
#pragma once

#include <ros/node_handle.h>
#include <xmlrpcpp/XmlRpcValue.h>
#include <yaml-cpp/yaml.h>

#include <string>

#include "io/estimator_config.h"

namespace pc_ekf {

// Private parameters that are not schema keys: the file name itself and
// diagnostic_updater's own period.
constexpr const char* kConfigFileParam = "config_file";
constexpr const char* kDiagnosticPeriodParam = "diagnostic_period";

// Parameter-server value -> YAML (doubles written so they read back exactly).
YAML::Node yamlFromXmlRpc(const XmlRpc::XmlRpcValue& value);
// Copies `overlay` into `base`: maps key by key (recursively), anything else replaced.
void mergeYaml(YAML::Node& base, const YAML::Node& overlay);

// Reads and validates the configuration of the node whose private
// NodeHandle is `private_nh`. Throws ConfigError naming the key and value.
EstimatorConfig loadRosConfig(const ros::NodeHandle& private_nh);

}  // namespace pc_ekf
