// A model's `vehicle:` section, read from its description's tables (the
// model layer knows no YAML; every model type is read the same way).
#pragma once

#include <memory>

#include "pc_ekf/model/model_description.h"

namespace pc_ekf {

class YamlMapReader;

// Reads the description's parameters, settings and choices from `section`
// over a copy of `base` (absent keys keep base's values), each checked
// against its domain; bad values fail through section.fail (ConfigError).
std::shared_ptr<ModelParameters> readVehicleSection(YamlMapReader& section,
                                                    const ModelDescription& description,
                                                    const ModelParameters& base);

}  // namespace pc_ekf
