#include "pc_ekf/model/mechanical_model.h"

#include <algorithm>
#include <stdexcept>

#include "pc_ekf/model/road_input.h"

namespace pc_ekf {

void ModelBatch::derivativesTransposed(double t, const Eigen::ArrayXXd& y_t,
                                       Eigen::ArrayXXd& dydt_t) const {
  const Eigen::ArrayXXd y = y_t.transpose();
  Eigen::ArrayXXd dydt(y.rows(), y.cols());
  derivatives(t, y, dydt);
  dydt_t = dydt.transpose();
}

std::string toString(ZeroConvention z) { return z == ZeroConvention::kTare ? "tare" : "rest"; }

ZeroConvention zeroConventionFromString(const std::string& name) {
  if (name == "rest") return ZeroConvention::kRest;
  if (name == "tare") return ZeroConvention::kTare;
  throw std::invalid_argument("zero convention '" + name + "': expected rest or tare");
}

int MechanicalModel::parameterIndex(const std::string& name) const {
  const auto& names = parameterNames();
  const auto it = std::find(names.begin(), names.end(), name);
  return it == names.end() ? -1 : static_cast<int>(it - names.begin());
}

void checkModelOnRoad(const MechanicalModel& model, const ContactRoad* road,
                      const std::string& who) {
  const std::size_t contacts = model.description().contactNames().size();
  if (!road) throw std::invalid_argument(who + ": no road input");
  if (static_cast<std::size_t>(road->contactCount()) != contacts) {
    throw std::invalid_argument(who + ": a road under " + std::to_string(contacts) +
                                " contacts expected, got " + std::to_string(road->contactCount()));
  }
  const std::string why = model.invalidReason(model.nominalParameters());
  if (!why.empty()) throw std::invalid_argument(who + ": nominal parameters: " + why);
}

}  // namespace pc_ekf
