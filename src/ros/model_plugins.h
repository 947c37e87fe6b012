// Models from other packages: a package exports ModelType subclasses with
// pluginlib (PLUGINLIB_EXPORT_CLASS(my_pkg::MyModelType, pc_ekf::ModelType),
// `<export><pc_ekf plugin="${prefix}/models.xml"/></export>` in its
// package.xml, the class named `my_pkg/MyModel` in models.xml) and a config
// selects it with `model: {type: my_pkg/MyModel}`. The same mechanism
// nodelet uses on this system.
#pragma once

#include "pc_ekf/model/model_type.h"

namespace pc_ekf {

// The built-in model types, then the plugins of every package on the ROS
// package path. A plugin name that no package declares, or whose library does
// not load, is an error naming it (std::runtime_error, reported by the config
// reader under model.type).
ModelRegistry modelRegistryWithPlugins();

}  // namespace pc_ekf
