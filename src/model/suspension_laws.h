// Pieces shared by the built-in vehicle models (and open to plugins): the
// damper laws, the spring increment about the static compression, the
// damper-law choice of the `vehicle:` section and the per-point constant table
// that prepare() fills so the right-hand side does no parameter work.
#pragma once

#include <Eigen/Dense>
#include <string>

#include "pc_ekf/model/model_description.h"
#include "pc_ekf/model/smooth_functions.h"

namespace pc_ekf {

// F_C = c * scale * tanh(rate * v) (kTanh) or F_C = c v (kLinear).
enum class DamperLaw { kTanh, kLinear };

template <DamperLaw law>
inline double damperForce(double damping, double tanh_rate, double v) {
  return law == DamperLaw::kTanh ? damping * fastTanh(tanh_rate * v) : damping * v;
}

// F_K(delta) - F_K(delta - u) for F_K(x) = k x + k3 x^3, expanded so that it
// is exactly 0 at u = 0 (docs/method.md §1.4).
inline double springIncrement(double u, double k, double k3, double three_delta,
                              double three_delta_sq) {
  return u * (k + k3 * (three_delta_sq - three_delta * u + u * u));
}

// The `damper` choice of a vehicle description and its settings.
ChoiceSpec damperChoice();
DamperLaw damperLaw(const std::string& choice);  // "tanh" | "linear", else invalid_argument
std::string damperChoiceName(DamperLaw law);
// A built vehicle's tanh constants must be finite and >= 0 (std::invalid_argument
// prefixed by `who`); the linear law ignores them.
void checkDamperSettings(const std::string& who, DamperLaw law, double tanh_scale,
                         double tanh_rate);

// Per-point constants: one Q x columns table, one contiguous column per
// quantity (structure of arrays over the Q points), so a loop over the points
// vectorises. Each model names its columns with an enum.
class PointConstantTable {
 public:
  PointConstantTable(Eigen::Index points, int columns) : table_(points, columns) {}
  double& operator()(Eigen::Index q, int column) { return table_(q, column); }
  Eigen::Index size() const { return table_.rows(); }
  const double* column(int c) const { return table_.col(c).data(); }

 private:
  Eigen::ArrayXXd table_;
};

}  // namespace pc_ekf
