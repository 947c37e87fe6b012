#include <stdexcept>

#include "pc_ekf/model/model_type.h"

namespace pc_ekf {

ModelRegistry::ModelRegistry() {
  add(rollPlaneType());
  add(fullCarType());
}

void ModelRegistry::add(std::shared_ptr<const ModelType> type) {
  if (!type) throw std::invalid_argument("ModelRegistry::add: no type");
  const std::string name = type->name();
  if (!builtin_.emplace(name, std::move(type)).second) {
    throw std::invalid_argument("ModelRegistry: model type '" + name + "' registered twice");
  }
}

const ModelRegistry& ModelRegistry::builtins() {
  static const ModelRegistry registry;
  return registry;
}

std::shared_ptr<const ModelType> ModelRegistry::find(const std::string& name) const {
  const auto it = builtin_.find(name);
  if (it != builtin_.end()) return it->second;
  for (const auto& r : resolvers_) {
    if (auto t = r(name)) return t;
  }
  return nullptr;
}

std::vector<std::string> ModelRegistry::builtinNames() const {
  std::vector<std::string> out;
  for (const auto& [name, type] : builtin_) out.push_back(name);
  return out;
}

}  // namespace pc_ekf
