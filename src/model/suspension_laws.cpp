#include "pc_ekf/model/suspension_laws.h"

#include <stdexcept>

namespace pc_ekf {

ChoiceSpec damperChoice() {
  return {"damper", {"tanh", "linear"}, "damper law: F_C = c scale tanh(rate v), or F_C = c v"};
}

DamperLaw damperLaw(const std::string& choice) {
  if (choice == "tanh") return DamperLaw::kTanh;
  if (choice == "linear") return DamperLaw::kLinear;
  throw std::invalid_argument("damper law '" + choice + "': tanh or linear expected");
}

std::string damperChoiceName(DamperLaw law) { return law == DamperLaw::kTanh ? "tanh" : "linear"; }

}  // namespace pc_ekf
