// The roll-plane bar as a model type: its description, its model on a road
// and its speed bump.
#include <cmath>
#include <cstdio>

#include "pc_ekf/model/model_type.h"
#include "pc_ekf/model/roll_plane_model.h"
#include "pc_ekf/model/roll_plane_road_free.h"

namespace pc_ekf {
namespace {

class RollPlaneType : public ModelType {
 public:
  const ModelDescription& description() const override { return rollPlaneDescription(); }
  std::shared_ptr<const MechanicalModel> build(const ModelParameters& p,
                                               std::shared_ptr<const ContactRoad> road) const override {
    return std::make_shared<RollPlaneModel>(p, std::move(road));
  }
  std::shared_ptr<const MechanicalModel> build(const ModelParameters& p,
                                               std::shared_ptr<const ContactRoad> road,
                                               const ReadingSettings& readings) const override {
    return std::make_shared<RollPlaneModel>(p, std::move(road), readings);
  }
  std::shared_ptr<const MechanicalModel> buildRoadFree(const ModelParameters& p,
                                                       std::shared_ptr<const ReadingInputs> in,
                                                       ZeroConvention zero) const override {
    return std::make_shared<RollPlaneRoadFreeModel>(VehicleParameters::from(p), std::move(in),
                                                    zero);
  }
  RoadFreeInputs roadFreeInputs() const override {
    const std::vector<std::string>& ch = rollPlaneChannels();  // u1 u2 v1 v2, gyro_x speed gyro_z
    return {{ch.begin(), ch.begin() + RollPlaneModel::kSuspensionChannels},
            {ch[6], ch[7], ch[8]},
            {ch[7], ch[8]}};
  }
  std::string equilibriumSummary(const ModelParameters& laws,
                                 const Eigen::VectorXd& values) const override {
    const VehicleParameters p =
        VehicleParameters::fromVector(values, VehicleParameters::from(laws));
    const StaticEquilibrium e = solveStaticEquilibrium(p);
    char line[160];
    std::snprintf(line, sizeof line,
                  "M = %.2f kg, d_CG = %.4f m -> theta_s = %.4f deg, h2 - h1 = %.5f m",
                  p.added_mass, p.added_mass_position, e.roll_angle * 180.0 / M_PI,
                  e.height[1] - e.height[0]);
    return line;
  }
};

}  // namespace

std::shared_ptr<const ModelType> rollPlaneType() {
  static const auto type = std::make_shared<const RollPlaneType>();
  return type;
}

}  // namespace pc_ekf
