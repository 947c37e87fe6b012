// Flat parameter vector of the full-car model and its admissibility rules.
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "pc_ekf/model/domain_message.h"
#include "pc_ekf/model/full_car_model.h"

namespace pc_ekf {

namespace {

constexpr int kCount = 19;


}  // namespace

const std::vector<std::string>& fullCarParameterNames() {
  static const std::vector<std::string> names = {
      "body_mass",           "roll_inertia",       "pitch_inertia",       "front_axle_distance",
      "rear_axle_distance",  "track_width",        "unsprung_mass_front", "unsprung_mass_rear",
      "spring_linear_front", "spring_linear_rear", "spring_cubic_front",  "spring_cubic_rear",
      "damping_front",       "damping_rear",       "tyre_stiffness",      "gravity",
      "added_mass",          "added_mass_x",       "added_mass_y"};
  return names;
}

Eigen::VectorXd FullCarParameters::toVector() const {
  Eigen::VectorXd v(kCount);
  v << body_mass, roll_inertia, pitch_inertia, front_axle_distance, rear_axle_distance, track_width,
      unsprung_mass[0], unsprung_mass[1], spring_linear[0], spring_linear[1], spring_cubic[0],
      spring_cubic[1], damping[0], damping[1], tyre_stiffness, gravity, added_mass, added_mass_x,
      added_mass_y;
  return v;
}

FullCarParameters FullCarParameters::fromVector(const Eigen::Ref<const Eigen::VectorXd>& v,
                                                const FullCarParameters& laws) {
  if (v.size() != kCount) {
    throw std::invalid_argument("FullCarParameters::fromVector: expected " +
                                std::to_string(kCount) + " values, got " +
                                std::to_string(v.size()));
  }
  FullCarParameters p = laws;
  p.body_mass = v[0];
  p.roll_inertia = v[1];
  p.pitch_inertia = v[2];
  p.front_axle_distance = v[3];
  p.rear_axle_distance = v[4];
  p.track_width = v[5];
  p.unsprung_mass[0] = v[6];
  p.unsprung_mass[1] = v[7];
  p.spring_linear[0] = v[8];
  p.spring_linear[1] = v[9];
  p.spring_cubic[0] = v[10];
  p.spring_cubic[1] = v[11];
  p.damping[0] = v[12];
  p.damping[1] = v[13];
  p.tyre_stiffness = v[14];
  p.gravity = v[15];
  p.added_mass = v[16];
  p.added_mass_x = v[17];
  p.added_mass_y = v[18];
  return p;
}

std::string fullCarParameterRuleViolation(const Eigen::Ref<const Eigen::VectorXd>& params) {
  const auto& names = fullCarParameterNames();
  if (params.size() != kCount) {
    return "expected " + std::to_string(kCount) + " parameters, got " +
           std::to_string(params.size());
  }
  for (Eigen::Index i = 0; i < kCount; ++i) {
    if (!std::isfinite(params[i])) return outOfDomain(names[i], params[i], "is not finite");
  }
  // Masses, inertias, lengths, linear and tyre stiffnesses, gravity.
  for (int i : {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 14, 15}) {
    if (params[i] <= 0.0) return outOfDomain(names[i], params[i], "must be > 0");
  }
  for (int i : {10, 11, 12, 13, 16}) {  // cubic stiffness, damping, added mass
    if (params[i] < 0.0) return outOfDomain(names[i], params[i], "must be >= 0");
  }
  const double wheelbase = params[3] + params[4], track = params[5];
  if (params[17] < 0.0 || params[17] > wheelbase) {
    return outOfDomain(names[17], params[17], "outside [0, " + domainNumber(wheelbase) + "]");
  }
  if (params[18] < 0.0 || params[18] > track) {
    return outOfDomain(names[18], params[18], "outside [0, " + domainNumber(track) + "]");
  }
  return "";
}

}  // namespace pc_ekf
