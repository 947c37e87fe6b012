// Everything a model declares about itself, in one value shared by its
// MechanicalModel (what the filters see) and its ModelType (what the config
// layer and the ROS edge see): its name, parameter table, settings (fixed
// numbers that are not estimated, e.g. damper constants), choices (e.g. the
// damper law), states, measurement channels, road contacts and suspension
// joints. Neither side declares a name of its own.
#pragma once

#include <Eigen/Dense>
#include <map>
#include <string>
#include <vector>

#include "pc_ekf/model/parameter_table.h"

namespace pc_ekf {

struct ChannelSpec {
  std::string name;
  std::string unit;
  std::string description;
  // In measurement.channels' default (false: an IMU channel, chosen by name).
  bool selected_by_default = true;
};

// A road contact (a tyre): its name (pc_ekf/RoadHeights, the road CSV header
// unless road_column is set) and a description.
struct ContactSpec {
  std::string name;
  std::string road_column;  // "" = name
  std::string description;
};

// One suspension: the JointState joint carrying its extension (position) and
// rate (velocity).
struct SuspensionJoint {
  std::string default_joint;  // e.g. left_suspension
  std::string config_key;     // key under node.joints, e.g. left
  int position_channel = -1;  // index into the channels
  int velocity_channel = -1;
};

// A keyword setting of the `vehicle:` section (e.g. damper: tanh | linear).
struct ChoiceSpec {
  std::string name;
  std::vector<std::string> options;  // the first is the default
  std::string description;
};

struct JointSpec {
  std::string default_joint, config_key;
  std::string position_channel, velocity_channel;  // channel names ("" = none)
};

class ModelDescription {
 public:
  struct Parts {
    std::string name;     // model.type
    std::string summary;  // one line
    ParameterTable parameters;
    ParameterTable settings;
    std::vector<ChoiceSpec> choices;
    std::vector<std::string> states;
    std::vector<ChannelSpec> channels;
    std::vector<ContactSpec> contacts;
    std::vector<JointSpec> joints;
  };
  // Throws std::invalid_argument for a joint naming an unknown channel.
  explicit ModelDescription(Parts parts);

  const std::string& name() const { return p_.name; }
  const std::string& summary() const { return p_.summary; }
  const ParameterTable& parameters() const { return p_.parameters; }
  const ParameterTable& settings() const { return p_.settings; }
  const std::vector<ChoiceSpec>& choices() const { return p_.choices; }
  const std::vector<std::string>& stateNames() const { return p_.states; }
  const std::vector<ChannelSpec>& channels() const { return p_.channels; }
  const std::vector<std::string>& channelNames() const { return channel_names_; }
  int channelIndex(const std::string& name) const;  // -1 when unknown
  // The channels with selected_by_default, in channel order.
  std::vector<std::string> defaultChannelNames() const;
  const std::vector<ContactSpec>& contacts() const { return p_.contacts; }
  const std::vector<std::string>& contactNames() const { return contact_names_; }
  const std::vector<std::string>& roadColumns() const { return road_columns_; }
  const std::vector<SuspensionJoint>& suspensions() const { return suspensions_; }
  int choiceIndex(const std::string& name) const;  // -1 when unknown

  // The doc section of the model (docs/models.md): tables of parameters,
  // settings, choices, channels, contacts and joints.
  std::string markdown() const;

 private:
  Parts p_;
  std::vector<std::string> channel_names_, contact_names_, road_columns_;
  std::vector<SuspensionJoint> suspensions_;
};

// A model's values: the parameter vector, the settings and the choices, each
// in the order of its description's tables.
struct ModelParameters {
  Eigen::VectorXd values;
  Eigen::VectorXd settings;
  std::vector<std::string> choices;
  // Tabulated laws a choice asks for, by name (e.g. damper_table_left when
  // damper is table: row 0 velocities, row 1 forces); empty otherwise.
  std::map<std::string, Eigen::MatrixXd> tables;
  static ModelParameters defaults(const ModelDescription& d);
  double setting(const ModelDescription& d, const std::string& name) const {
    return settings[d.settings().at(name)];
  }
  const std::string& choice(const ModelDescription& d, const std::string& name) const;
};

}  // namespace pc_ekf
