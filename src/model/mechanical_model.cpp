#include "pc_ekf/model/mechanical_model.h"

#include <algorithm>
#include <stdexcept>

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

}  // namespace pc_ekf
