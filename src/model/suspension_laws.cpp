#include "pc_ekf/model/suspension_laws.h"

#include <cmath>
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

void checkDamperSettings(const std::string& who, DamperLaw law, double tanh_scale,
                         double tanh_rate) {
  if (law == DamperLaw::kTanh && !(std::isfinite(tanh_scale) && std::isfinite(tanh_rate) &&
                                   tanh_scale >= 0.0 && tanh_rate >= 0.0)) {
    throw std::invalid_argument(who + ": damper tanh scale and rate must be finite, >= 0");
  }
}

}  // namespace pc_ekf
