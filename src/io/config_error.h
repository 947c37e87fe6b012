// The error of a bad configuration, thrown by the YAML reader (yaml_reader.h)
// and by everything that reads or checks a config, a vehicle file or a
// tolerances: section.
#pragma once

#include <stdexcept>

namespace pc_ekf {

// Bad configuration: the message names the source, the key, the value and
// what was expected.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace pc_ekf
