// Flat parameter vector of the roll-plane model, in the order of roll_plane_model.h.
#include <stdexcept>

#include "pc_ekf/model/roll_plane_model.h"

namespace pc_ekf {

const std::vector<std::string>& vehicleParameterNames() {
  static const std::vector<std::string> names = {"bar_mass",
                                                 "unsprung_mass_left",
                                                 "unsprung_mass_right",
                                                 "damping_left",
                                                 "damping_right",
                                                 "spring_linear_left",
                                                 "spring_linear_right",
                                                 "spring_cubic_left",
                                                 "spring_cubic_right",
                                                 "bar_length",
                                                 "bar_inertia",
                                                 "tyre_stiffness_left",
                                                 "tyre_stiffness_right",
                                                 "gravity",
                                                 "added_mass",
                                                 "added_mass_position"};
  return names;
}

Eigen::VectorXd VehicleParameters::toVector() const {
  Eigen::VectorXd v(16);
  v << bar_mass, unsprung_mass[0], unsprung_mass[1], damping[0], damping[1], spring_linear[0],
      spring_linear[1], spring_cubic[0], spring_cubic[1], bar_length, bar_inertia,
      tyre_stiffness[0], tyre_stiffness[1], gravity, added_mass, added_mass_position;
  return v;
}

VehicleParameters VehicleParameters::fromVector(const Eigen::Ref<const Eigen::VectorXd>& v,
                                                const VehicleParameters& laws) {
  if (v.size() != 16) {
    throw std::invalid_argument("VehicleParameters::fromVector: expected 16 values, got " +
                                std::to_string(v.size()));
  }
  VehicleParameters p = laws;  // damper law and tanh constants are not in the vector
  p.bar_mass = v[0];
  p.unsprung_mass[0] = v[1];
  p.unsprung_mass[1] = v[2];
  p.damping[0] = v[3];
  p.damping[1] = v[4];
  p.spring_linear[0] = v[5];
  p.spring_linear[1] = v[6];
  p.spring_cubic[0] = v[7];
  p.spring_cubic[1] = v[8];
  p.bar_length = v[9];
  p.bar_inertia = v[10];
  p.tyre_stiffness[0] = v[11];
  p.tyre_stiffness[1] = v[12];
  p.gravity = v[13];
  p.added_mass = v[14];
  p.added_mass_position = v[15];
  return p;
}

}  // namespace pc_ekf
