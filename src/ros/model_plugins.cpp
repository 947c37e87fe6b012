#include "pc_ekf/ros/model_plugins.h"

#include <pluginlib/class_loader.hpp>

#include <memory>
#include <stdexcept>

namespace pc_ekf {

ModelRegistry modelRegistryWithPlugins() {
  ModelRegistry registry;
  // One loader, created on the first plugin name and kept alive by every
  // instance it made (a library must stay loaded while its objects live).
  auto loader = std::make_shared<std::shared_ptr<pluginlib::ClassLoader<ModelType>>>();
  registry.addResolver([loader](const std::string& name) -> std::shared_ptr<const ModelType> {
    if (name.find('/') == std::string::npos) return nullptr;  // plugins are package/Class
    if (!*loader) {
      *loader = std::make_shared<pluginlib::ClassLoader<ModelType>>("pc_ekf", "pc_ekf::ModelType");
    }
    const auto keep = *loader;
    if (!keep->isClassAvailable(name)) {
      std::string declared;
      for (const auto& c : keep->getDeclaredClasses()) declared += (declared.empty() ? "" : ", ") + c;
      throw std::runtime_error("no package exports model plugin '" + name + "'" +
                               (declared.empty() ? std::string(" (none declared)")
                                                 : " (declared: " + declared + ")"));
    }
    try {
      // The object goes before its loader (a library must outlive its objects).
      struct Owner {
        std::shared_ptr<ModelType> instance;
        std::shared_ptr<pluginlib::ClassLoader<ModelType>> loader;
        void operator()(const ModelType*) {
          instance.reset();
          loader.reset();
        }
      };
      std::shared_ptr<ModelType> instance = keep->createSharedInstance(name);
      ModelType* raw = instance.get();
      return std::shared_ptr<const ModelType>(raw, Owner{std::move(instance), keep});
    } catch (const pluginlib::PluginlibException& e) {
      throw std::runtime_error("model plugin '" + name + "' did not load: " + e.what());
    }
  });
  return registry;
}

}  // namespace pc_ekf
