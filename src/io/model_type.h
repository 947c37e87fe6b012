// What a mechanical model is to the configuration layer and the tools: its
// parameter names and YAML reader (the `vehicle:` section), its contacts
// (road inputs), its channels and suspensions (CSV columns, JointState
// mapping), and how to build it on a road. The filters see only the
// MechanicalModel it builds. Built-in types: roll_plane (the paper's bar),
// full_car; others come from plugins (ModelRegistry::addResolver).
#pragma once

#include <Eigen/Dense>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "pc_ekf/model/mechanical_model.h"
#include "pc_ekf/model/road_input.h"

namespace pc_ekf {

class YamlMapReader;

// A model's fixed settings as read from YAML: the full parameter vector (in
// parameterNames() order) plus whatever laws the type keeps (a subclass).
struct ModelParameters {
  virtual ~ModelParameters() = default;
  Eigen::VectorXd values;
};

// One suspension: the JointState joint carrying its extension (position) and
// rate (velocity).
struct SuspensionJoint {
  std::string default_joint;  // e.g. left_suspension
  std::string config_key;     // key under node.joints, e.g. left
  int position_channel = -1;  // index into channelNames()
  int velocity_channel = -1;
};

class ModelType {
 public:
  virtual ~ModelType() = default;
  virtual std::string name() const = 0;
  virtual const std::vector<std::string>& parameterNames() const = 0;
  virtual const std::vector<std::string>& contactNames() const = 0;
  // Road CSV columns after t (default: the contact names).
  virtual std::vector<std::string> roadColumns() const { return contactNames(); }
  virtual const std::vector<std::string>& channelNames() const = 0;
  virtual const std::vector<SuspensionJoint>& suspensions() const = 0;

  virtual std::shared_ptr<ModelParameters> defaults() const = 0;
  // Reads the model's keys from `section` over a copy of `base` (absent keys
  // keep base's values); bad values fail through section.fail (ConfigError).
  virtual std::shared_ptr<ModelParameters> read(YamlMapReader& section,
                                                const ModelParameters& base) const = 0;
  // Throws std::invalid_argument when the road has the wrong contact count.
  virtual std::shared_ptr<const MechanicalModel> build(
      const ModelParameters& parameters, std::shared_ptr<const ContactRoad> road) const = 0;
  // The analytic speed bump under this model's contacts (road.speed_bump).
  virtual std::shared_ptr<const ContactRoad> speedBump(const SpeedBumpSettings& s,
                                                       const ModelParameters& parameters) const = 0;
  // The two-contact analytic roads (sine, course): only for two-contact models.
  bool twoContacts() const { return contactNames().size() == 2; }
};

std::shared_ptr<const ModelType> rollPlaneType();
std::shared_ptr<const ModelType> fullCarType();

// The roll plane's settings as VehicleParameters and back (roll_plane only).
struct VehicleParameters;
VehicleParameters rollPlaneVehicle(const ModelParameters& p);
std::shared_ptr<ModelParameters> rollPlaneParameters(const VehicleParameters& v);

// Model types by name: the built-ins, then resolvers (e.g. a plugin loader)
// for names it does not know. Immutable once built.
class ModelRegistry {
 public:
  using Resolver = std::function<std::shared_ptr<const ModelType>(const std::string& name)>;
  ModelRegistry();  // the built-ins
  static const ModelRegistry& builtins();
  void addResolver(Resolver r) { resolvers_.push_back(std::move(r)); }
  // nullptr when no type of that name is known; resolvers may throw
  // std::runtime_error naming why a plugin could not be loaded.
  std::shared_ptr<const ModelType> find(const std::string& name) const;
  std::vector<std::string> builtinNames() const;

 private:
  std::map<std::string, std::shared_ptr<const ModelType>> builtin_;
  std::vector<Resolver> resolvers_;
};

}  // namespace pc_ekf
