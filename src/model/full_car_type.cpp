// The 7-DOF full car as a model type: its description, its model on a road
// and its four-wheel speed bump.
#include <cmath>
#include <cstdio>

#include "pc_ekf/model/model_type.h"
#include "pc_ekf/model/full_car_model.h"
#include "pc_ekf/model/full_car_road_free.h"
#include "pc_ekf/model/full_car_road.h"

namespace pc_ekf {
namespace {

class FullCarType : public ModelType {
 public:
  const ModelDescription& description() const override { return fullCarDescription(); }
  std::shared_ptr<const MechanicalModel> build(const ModelParameters& p,
                                               std::shared_ptr<const ContactRoad> road) const override {
    return std::make_shared<FullCarModel>(p, std::move(road));
  }
  std::shared_ptr<const MechanicalModel> build(const ModelParameters& p,
                                               std::shared_ptr<const ContactRoad> road,
                                               const ReadingSettings& readings) const override {
    return std::make_shared<FullCarModel>(p, std::move(road), readings);
  }
  std::shared_ptr<const MechanicalModel> buildRoadFree(const ModelParameters& p,
                                                       std::shared_ptr<const ReadingInputs> in,
                                                       ZeroConvention zero) const override {
    return std::make_shared<FullCarRoadFreeModel>(FullCarParameters::from(p), std::move(in), zero);
  }
  RoadFreeInputs roadFreeInputs() const override {
    return {{"u_fl", "u_fr", "u_rl", "u_rr", "v_fl", "v_fr", "v_rl", "v_rr"}, {"gyro_x", "gyro_y", "speed", "gyro_z", "accel_x"},
            {"speed", "gyro_z"}};
  }
  // Front wheels on the tracks, rear wheels a wheelbase behind them.
  std::shared_ptr<const ContactRoad> drivenProfile(std::shared_ptr<const TrackProfile> profile,
                                                   double speed,
                                                   const ModelParameters& p) const override {
    const double wb = FullCarParameters::from(p).wheelbase();
    return std::make_shared<DrivenProfileRoad>(
        std::move(profile), speed,
        std::vector<std::pair<int, double>>{{0, 0.0}, {1, 0.0}, {0, wb}, {1, wb}});
  }
  std::shared_ptr<const ContactRoad> speedBump(const SpeedBumpSettings& s,
                                               const ModelParameters& p) const override {
    FullCarBumpSettings b;
    b.bump = s;
    b.wheelbase = FullCarParameters::from(p).wheelbase();
    return std::make_shared<FullCarBumpRoad>(b);
  }
  // Front wheels on the course's tracks, rear wheels a wheelbase behind.
  std::shared_ptr<const ContactRoad> course(const std::vector<CourseSegment>& segments,
                                            const ModelParameters& p) const override {
    return std::make_shared<FullCarCourseRoad>(segments, FullCarParameters::from(p).wheelbase());
  }
  std::string equilibriumSummary(const ModelParameters& laws,
                                 const Eigen::VectorXd& values) const override {
    const FullCarParameters p =
        FullCarParameters::fromVector(values, FullCarParameters::from(laws));
    const FullCarEquilibrium e = solveFullCarEquilibrium(p);
    char line[200];
    std::snprintf(line, sizeof line,
                  "M = %.2f kg at x = %.4f m, y = %.4f m -> heave %.5f m, pitch %.4f deg "
                  "(> 0 front up), roll %.4f deg (> 0 left up)",
                  p.added_mass, p.added_mass_x, p.added_mass_y, e.heave, e.pitch * 180.0 / M_PI,
                  e.roll * 180.0 / M_PI);
    return line;
  }
};

}  // namespace

std::shared_ptr<const ModelType> fullCarType() {
  static const auto type = std::make_shared<const FullCarType>();
  return type;
}

}  // namespace pc_ekf
