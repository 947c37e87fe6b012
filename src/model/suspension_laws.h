// Pieces shared by the built-in vehicle models (and open to plugins): the
// damper laws, the spring increment about the static compression, the
// damper-law choice of the `vehicle:` section and the per-point constant table
// that prepare() fills so the right-hand side does no parameter work.
#pragma once

#include <Eigen/Dense>
#include <string>
#include <vector>

#include "pc_ekf/model/model_description.h"
#include "pc_ekf/model/smooth_functions.h"

namespace pc_ekf {

// F_C = c * scale * tanh(rate * v) (kTanh), F_C = c v (kLinear), or a
// measured curve scaled by c / its reference damping (kTable, DamperCurve).
enum class DamperLaw { kTanh, kLinear, kTable };

// A measured damper, force against extension rate at the wheel (v > 0
// rebound, v < 0 bump): linear between the points, through (0, 0), and
// extrapolated linearly beyond the first and last points with the end
// segments' slopes. Velocities strictly increasing, forces non-decreasing.
class DamperCurve {
 public:
  DamperCurve() = default;
  // points: row 0 velocities (m/s), row 1 forces (N), columns in increasing
  // velocity with one column (0, 0) and at least one on each side of it;
  // std::invalid_argument naming `who` otherwise.
  DamperCurve(const Eigen::MatrixXd& points, const std::string& who);
  double operator()(double v) const {
    // Segment j spans [v_j, v_j+1]; the first and last extend to -inf, +inf.
    std::size_t j = 0;
    const std::size_t last = velocity_.size() - 2;
    while (j < last && v > velocity_[j + 1]) ++j;
    return force_[j] + (v - velocity_[j]) * slope_[j];
  }
  // The mean of the bump and rebound slopes at 0 (the segments that touch
  // (0, 0)): the damping c of the curve as measured; the model's force is
  // F_C = c / reference_damping * curve(v).
  double referenceDamping() const { return reference_; }
  const std::vector<double>& velocity() const { return velocity_; }
  const std::vector<double>& force() const { return force_; }

 private:
  std::vector<double> velocity_, force_, slope_;
  double reference_ = 0.0;
};

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
// The same with `table` (a model that evaluates DamperCurve: the roll plane).
ChoiceSpec damperChoiceWithTable();
DamperLaw damperLaw(const std::string& choice);  // "tanh" | "linear" | "table", else invalid_argument
std::string damperChoiceName(DamperLaw law);
// A built vehicle's tanh constants must be finite and >= 0 (std::invalid_argument
// prefixed by `who`); the linear law ignores them; the table law is refused
// (a model with curves checks them itself: rollPlaneDamperCurves).
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
