// The nonlinear 4-DOF roll-plane vehicle model of docs/method.md §1.
//
// State (deviations from the static equilibrium, up positive):
//   [x1, x2, xr1, xr2, x1dot, x2dot, xr1dot, xr2dot]
// Channels: [u1, u2, v1, v2], u_i = x_i - xr_i, v_i = xidot - xridot.
#pragma once

#include <memory>

#include "pc_ekf/model/mechanical_model.h"
#include "pc_ekf/model/road_input.h"

namespace pc_ekf {

enum class DamperLaw { kTanh, kLinear };

// Names of the full parameter vector, in order (docs/method.md §1.1).
//   bar_mass, unsprung_mass_left, unsprung_mass_right, damping_left, damping_right,
//   spring_linear_left, spring_linear_right, spring_cubic_left, spring_cubic_right,
//   bar_length, bar_inertia, tyre_stiffness_left, tyre_stiffness_right, gravity,
//   added_mass, added_mass_position
struct VehicleParameters {
  double bar_mass = 580.0;
  double unsprung_mass[2] = {36.26, 36.26};
  double damping[2] = {710.70, 710.70};
  double spring_linear[2] = {19357.2, 19357.2};
  double spring_cubic[2] = {100000.0, 100000.0};
  double bar_length = 1.524;
  double bar_inertia = 63.3316;
  double tyre_stiffness[2] = {96319.76, 96319.76};
  double gravity = 9.81;
  double added_mass = 200.0;
  double added_mass_position = 0.762;
  DamperLaw damper = DamperLaw::kTanh;
  double damper_tanh_scale = 0.2;  // F_C = c * scale * tanh(rate * v)
  double damper_tanh_rate = 10.0;

  Eigen::VectorXd toVector() const;
  static VehicleParameters fromVector(const Eigen::Ref<const Eigen::VectorXd>& v,
                                      const VehicleParameters& laws);
};

const std::vector<std::string>& vehicleParameterNames();

// Static equilibrium of docs/method.md §1.3 for one parameter vector.
struct StaticEquilibrium {
  double combined_cg = 0.0;            // D, from the left end
  double spring_compression[2] = {0, 0};  // delta_i
  double load[2] = {0, 0};             // W_i
  double height[2] = {0, 0};           // h_i
  double roll_angle = 0.0;             // theta_s (rad)
};
// Newton on the cubic spring law; throws std::runtime_error if it fails to converge.
StaticEquilibrium solveStaticEquilibrium(const VehicleParameters& p);
// The same for many parameter sets at once (each result identical to the single
// solve; the Newton iterations of all springs advance together, which is faster).
std::vector<StaticEquilibrium> solveStaticEquilibria(const std::vector<VehicleParameters>& ps);

class RollPlaneModel : public MechanicalModel {
 public:
  // road: two contacts (left, right), else std::invalid_argument.
  RollPlaneModel(const VehicleParameters& nominal, std::shared_ptr<const ContactRoad> road);

  int stateSize() const override { return 8; }
  const std::vector<std::string>& stateNames() const override;
  const std::vector<std::string>& parameterNames() const override;
  const Eigen::VectorXd& nominalParameters() const override { return nominal_vector_; }
  std::string invalidReason(const Eigen::Ref<const Eigen::VectorXd>& params) const override;
  const std::vector<std::string>& channelNames() const override;
  const Eigen::MatrixXd& observationMatrix() const override { return h_; }
  std::unique_ptr<ModelBatch> prepare(const Eigen::MatrixXd& params) const override;
  std::vector<double> breakpoints(double t0, double t1) const override;

  const VehicleParameters& nominal() const { return nominal_; }
  const ContactRoad& road() const { return *road_; }
  const ContactRoad* contactRoad() const override { return road_.get(); }

 private:
  VehicleParameters nominal_;
  Eigen::VectorXd nominal_vector_;
  Eigen::MatrixXd h_;
  std::shared_ptr<const ContactRoad> road_;
};

}  // namespace pc_ekf
