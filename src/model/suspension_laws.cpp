#include "pc_ekf/model/suspension_laws.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace pc_ekf {

ChoiceSpec damperChoice() {
  return {"damper", {"tanh", "linear"}, "damper law: F_C = c scale tanh(rate v), or F_C = c v"};
}

ChoiceSpec damperChoiceWithTable() {
  return {"damper",
          {"tanh", "linear", "table"},
          "damper law: F_C = c scale tanh(rate v), F_C = c v, or the measured curve "
          "(vehicle.damper_table) scaled by c / its slope at 0"};
}

DamperLaw damperLaw(const std::string& choice) {
  if (choice == "tanh") return DamperLaw::kTanh;
  if (choice == "linear") return DamperLaw::kLinear;
  if (choice == "table") return DamperLaw::kTable;
  throw std::invalid_argument("damper law '" + choice + "': tanh, linear or table expected");
}

std::string damperChoiceName(DamperLaw law) {
  return law == DamperLaw::kTanh ? "tanh" : law == DamperLaw::kLinear ? "linear" : "table";
}

DamperCurve::DamperCurve(const Eigen::MatrixXd& points, const std::string& who) {
  const Eigen::Index n = points.cols();
  if (points.rows() != 2 || n < 3) {
    throw std::invalid_argument(who + ": a damper curve needs (0, 0) and a point on each side");
  }
  int zero = -1;
  for (Eigen::Index j = 0; j < n; ++j) {
    const double v = points(0, j), f = points(1, j);
    if (!std::isfinite(v) || !std::isfinite(f)) {
      throw std::invalid_argument(who + ": damper curve values must be finite");
    }
    if (j > 0 && !(v > points(0, j - 1))) {
      throw std::invalid_argument(who + ": damper curve velocities must increase strictly");
    }
    if (j > 0 && f < points(1, j - 1)) {
      throw std::invalid_argument(who + ": damper curve not monotone (the force falls between " +
                                  std::to_string(points(0, j - 1)) + " and " +
                                  std::to_string(v) + " m/s)");
    }
    if (v == 0.0) {
      if (f != 0.0) throw std::invalid_argument(who + ": damper curve must pass through (0, 0)");
      zero = static_cast<int>(j);
    }
  }
  if (zero <= 0 || zero >= n - 1) {
    throw std::invalid_argument(who + ": damper curve needs (0, 0) and a point on each side");
  }
  for (Eigen::Index j = 0; j < n; ++j) {
    velocity_.push_back(points(0, j));
    force_.push_back(points(1, j));
  }
  for (Eigen::Index j = 0; j + 1 < n; ++j) {
    slope_.push_back((force_[j + 1] - force_[j]) / (velocity_[j + 1] - velocity_[j]));
  }
  reference_ = 0.5 * (slope_[zero - 1] + slope_[zero]);
  if (!(reference_ > 0.0)) {
    throw std::invalid_argument(who + ": damper curve must have a positive slope at 0");
  }
}

void checkDamperSettings(const std::string& who, DamperLaw law, double tanh_scale,
                         double tanh_rate) {
  if (law == DamperLaw::kTable) {
    throw std::invalid_argument(who + ": damper law table needs a model that evaluates its curve "
                                      "(the roll plane)");
  }
  if (law == DamperLaw::kTanh && !(std::isfinite(tanh_scale) && std::isfinite(tanh_rate) &&
                                   tanh_scale >= 0.0 && tanh_rate >= 0.0)) {
    throw std::invalid_argument(who + ": damper tanh scale and rate must be finite, >= 0");
  }
}

}  // namespace pc_ekf
