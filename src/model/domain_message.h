// The wording of a physical-domain violation, shared by the models'
// invalidReason(): "name = value why", the value with 10 significant digits.
#pragma once

#include <sstream>
#include <string>

namespace pc_ekf {

inline std::string outOfDomain(const std::string& name, double value, const std::string& why) {
  std::ostringstream os;
  os.precision(10);
  os << name << " = " << value << " " << why;
  return os.str();
}

// A number as outOfDomain prints it (for bounds inside `why`).
inline std::string domainNumber(double value) {
  std::ostringstream os;
  os.precision(10);
  os << value;
  return os.str();
}

}  // namespace pc_ekf
