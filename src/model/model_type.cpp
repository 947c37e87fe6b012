// ModelType's defaults: the speed bump and the road by distance under one or
// two contacts, the reading conventions, the tables' defaults.
#include "pc_ekf/model/model_type.h"

#include <stdexcept>

namespace pc_ekf {

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

std::shared_ptr<const ContactRoad> ModelType::course(const std::vector<CourseSegment>& segments,
                                                    const ModelParameters&) const {
  if (contactNames().size() == 2) return std::make_shared<CourseRoad>(segments);
  throw std::invalid_argument(name() + ": no course road for " +
                              std::to_string(contactNames().size()) + " contacts");
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

}  // namespace pc_ekf
