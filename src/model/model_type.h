// Model types (ModelType), the built-in ones and the registry that finds them
// by name. Reading a type's `vehicle:` section belongs to the configuration
// layer (readVehicleSection), which reads it from the description's tables.
#pragma once

#include <Eigen/Dense>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "pc_ekf/model/mechanical_model.h"
#include "pc_ekf/model/road_input.h"
#include "pc_ekf/model/reading_inputs.h"
#include "pc_ekf/model/road_profile.h"

namespace pc_ekf {

// What a model is to the configuration layer, the tools and the ROS edge: its
// description (the same object its MechanicalModel returns: names, tables,
// channels, contacts, joints; the configuration layer reads `vehicle:` from
// its tables) and how to build it on a road. Built-in types (roll_plane,
// full_car) and plugins implement the same virtuals and are found through the
// same ModelRegistry.
class ModelType {
 public:
  virtual ~ModelType() = default;
  virtual const ModelDescription& description() const = 0;
  // Throws std::invalid_argument when the road has the wrong contact count.
  virtual std::shared_ptr<const MechanicalModel> build(
      const ModelParameters& parameters, std::shared_ptr<const ContactRoad> road) const = 0;
  // The same, reading as `readings` says (IMU channels, measurement.zero).
  // Default: the model above for the paper's convention; a model without
  // readings as states throws std::invalid_argument for anything else.
  virtual std::shared_ptr<const MechanicalModel> build(const ModelParameters& parameters,
                                                       std::shared_ptr<const ContactRoad> road,
                                                       const ReadingSettings& readings) const;
  // The analytic speed bump under this model's contacts (road.speed_bump).
  // Default: one contact takes the left track, two take left and right;
  // other counts throw std::invalid_argument (override it).
  virtual std::shared_ptr<const ContactRoad> speedBump(const SpeedBumpSettings& s,
                                                       const ModelParameters& parameters) const;
  // The course road (road.source course) under this model's contacts.
  // Default: two contacts take the course's tracks (CourseRoad); other
  // counts throw std::invalid_argument (override it).
  virtual std::shared_ptr<const ContactRoad> course(const std::vector<CourseSegment>& segments,
                                                    const ModelParameters& parameters) const;
  // Road-free form (road.source: none): the model driven by the readings
  // `roadFreeInputs()` names (in that order; the optional ones when the
  // record has them). Default: none (std::invalid_argument).
  virtual std::shared_ptr<const MechanicalModel> buildRoadFree(
      const ModelParameters& parameters, std::shared_ptr<const ReadingInputs> inputs,
      ZeroConvention zero) const;
  struct RoadFreeInputs {
    std::vector<std::string> required, optional;
    // Optional inputs of the vehicle's horizontal motion (speed, yaw rate):
    // an input whenever selected, 0 (straight, steady) until first read, so
    // that a stream without odometry, or odometry that starts late, is read.
    std::vector<std::string> zero_until_read;
  };
  virtual RoadFreeInputs roadFreeInputs() const { return {}; }
  // A road by distance (left and right tracks) driven at `speed` m/s under
  // this model's contacts (road.source iso8608, profile). Default: one
  // contact takes the left track, two take left and right; other counts
  // throw std::invalid_argument (override it).
  virtual std::shared_ptr<const ContactRoad> drivenProfile(
      std::shared_ptr<const TrackProfile> profile, double speed,
      const ModelParameters& parameters) const;
  // One line on the static equilibrium at the parameter vector `values`
  // (simulate_vehicle); "" when the model has nothing to say.
  virtual std::string equilibriumSummary(const ModelParameters&, const Eigen::VectorXd&) const {
    return "";
  }

  const std::string& name() const { return description().name(); }
  const std::vector<std::string>& parameterNames() const {
    return description().parameters().names();
  }
  const std::vector<std::string>& contactNames() const { return description().contactNames(); }
  // Road CSV columns after t.
  const std::vector<std::string>& roadColumns() const { return description().roadColumns(); }
  const std::vector<std::string>& channelNames() const { return description().channelNames(); }
  const std::vector<SuspensionJoint>& suspensions() const { return description().suspensions(); }
  // The two-contact analytic roads (sine, course): only for two-contact models.
  bool twoContacts() const { return contactNames().size() == 2; }

  // The tables' defaults.
  std::shared_ptr<ModelParameters> defaults() const;
};

// A plugin's type in one line: Model derives from PointwiseModel, has
// `static const ModelDescription& describe()` and a constructor
// (const Eigen::VectorXd& nominal, std::shared_ptr<const ContactRoad> road).
template <class Model>
class PointwiseModelType : public ModelType {
 public:
  const ModelDescription& description() const override { return Model::describe(); }
  std::shared_ptr<const MechanicalModel> build(
      const ModelParameters& p, std::shared_ptr<const ContactRoad> road) const override {
    return std::make_shared<Model>(p.values, std::move(road));
  }
};

std::shared_ptr<const ModelType> rollPlaneType();
std::shared_ptr<const ModelType> fullCarType();

// Model types by name: registered types (the built-ins are registered with
// add() like any other), then resolvers (e.g. the pluginlib loader) for names
// it does not know.
class ModelRegistry {
 public:
  using Resolver = std::function<std::shared_ptr<const ModelType>(const std::string& name)>;
  ModelRegistry();  // the built-ins
  static const ModelRegistry& builtins();
  // Throws std::invalid_argument when a type of that name is already registered.
  void add(std::shared_ptr<const ModelType> type);
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
