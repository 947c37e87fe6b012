// A vehicle file: a `vehicle:` section (every value of the model) and a
// `tolerances:` section (what is still uncertain about them), as written by
// calibrate_vehicle and read through a config's `vehicle_file: PATH`.
#pragma once

#include <string>
#include <vector>

#include "pc_ekf/filter/uncertain_parameters.h"
#include "pc_ekf/io/number_text.h"

namespace YAML {
class Node;
}

namespace pc_ekf {

// A relative `vehicle_file` of `root` becomes relative to the directory of
// `config_path` (the config file it was written in).
void anchorVehicleFile(YAML::Node& root, const std::string& config_path);

// `root` with the vehicle file merged in and its `vehicle_file` key removed:
// the file's `vehicle:` keys replace the config's, its `tolerances:` entries
// replace the config's of the same name (others stay). `path` receives the
// file's path ("" without one). ConfigError naming the file on a bad file.
YAML::Node mergeVehicleFile(const YAML::Node& root, const std::string& source, std::string* path);

// What calibrate_vehicle writes.
struct VehicleFile {
  std::vector<std::string> header;  // comment lines (without '#')
  // The `vehicle:` section: (key, YAML scalar text) in order.
  std::vector<std::pair<std::string, std::string>> vehicle;
  // Remaining uncertainty; `nominal` is written when it differs from the
  // vehicle value, the germ when it is not Beta(2, 2).
  std::vector<UncertainParameter> tolerances;
};
// YAML text of `file`; numbers in shortest round-trip form (roundTripText).
std::string vehicleFileText(const VehicleFile& file);

}  // namespace pc_ekf
