#include "model/mechanical_model.h"

#include <algorithm>

namespace pc_ekf {

int MechanicalModel::parameterIndex(const std::string& name) const {
  const auto& names = parameterNames();
  const auto it = std::find(names.begin(), names.end(), name);
  return it == names.end() ? -1 : static_cast<int>(it - names.begin());
}

}  // namespace pc_ekf
