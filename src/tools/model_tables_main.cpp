// model_tables: the description tables (parameters, settings, choices,
// channels, contacts, joints) of every built-in model type, or of the types
// named on the command line (plugins included), as Markdown (docs/models.md).
#include <cstdio>
#include <iostream>
#include <string>

#include "pc_ekf/ros/model_plugins.h"

int main(int argc, char** argv) {
  using namespace pc_ekf;
  try {
    const ModelRegistry registry = modelRegistryWithPlugins();
    std::vector<std::string> names(argv + 1, argv + argc);
    if (names.empty()) names = registry.builtinNames();
    for (std::size_t i = 0; i < names.size(); ++i) {
      const auto type = registry.find(names[i]);
      if (!type) {
        std::cerr << "model_tables: unknown model type '" << names[i] << "'\n";
        return 2;
      }
      std::printf("%s%s", i ? "\n" : "", type->description().markdown().c_str());
    }
  } catch (const std::exception& e) {
    std::cerr << "model_tables: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
