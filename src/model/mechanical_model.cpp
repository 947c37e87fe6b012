#include "pc_ekf/model/mechanical_model.h"

#include <algorithm>

namespace pc_ekf {

void ModelBatch::derivativesTransposed(double t, const Eigen::ArrayXXd& y_t,
                                       Eigen::ArrayXXd& dydt_t) const {
  const Eigen::ArrayXXd y = y_t.transpose();
  Eigen::ArrayXXd dydt(y.rows(), y.cols());
  derivatives(t, y, dydt);
  dydt_t = dydt.transpose();
}

int MechanicalModel::parameterIndex(const std::string& name) const {
  const auto& names = parameterNames();
  const auto it = std::find(names.begin(), names.end(), name);
  return it == names.end() ? -1 : static_cast<int>(it - names.begin());
}

}  // namespace pc_ekf
