// estimator_node configuration from the parameter server: the same YAML
// schema as the CLIs (config/speed_bump.yaml), read from the file named by
// ~config_file and/or the private namespace itself (`rosparam load FILE
// /estimator_node`). Private parameters override the file, maps merged key
// by key.
#pragma once

#include <ros/node_handle.h>
#include <xmlrpcpp/XmlRpcValue.h>
#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <string>

#include "pc_ekf/io/estimator_config.h"

namespace pc_ekf {

// Private parameters that are not schema keys: the file name itself,
// diagnostic_updater's own period and the checkpoint settings (docs/reliability.md
// "Checkpoints"; node only, so the CLIs' schema is unaffected).
constexpr const char* kConfigFileParam = "config_file";
constexpr const char* kDiagnosticPeriodParam = "diagnostic_period";
constexpr const char* kCheckpointFileParam = "checkpoint_file";
constexpr const char* kCheckpointEveryParam = "checkpoint_every";

// Parameter-server value -> YAML (doubles written so they read back exactly).
YAML::Node yamlFromXmlRpc(const XmlRpc::XmlRpcValue& value);
// Copies `overlay` into `base`: maps key by key (recursively), anything else replaced.
void mergeYaml(YAML::Node& base, const YAML::Node& overlay);

// Reads and validates the configuration of the node whose private
// NodeHandle is `private_nh`. Throws ConfigError naming the key and value.
// `config_hash` (optional): FNV-1a of canonicalConfigText() of the merged
// YAML (file + private parameters), for checkpoints.
EstimatorConfig loadRosConfig(const ros::NodeHandle& private_nh,
                              std::uint64_t* config_hash = nullptr);

}  // namespace pc_ekf
