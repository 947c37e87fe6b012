// The nonlinear 4-DOF roll-plane vehicle model of docs/method.md §1.
//
// State (deviations from the static equilibrium, up positive):
//   [x1, x2, xr1, xr2, x1dot, x2dot, xr1dot, xr2dot]
// Channels: [u1, u2, v1, v2], u_i = x_i - xr_i, v_i = xidot - xridot, then
// the IMU's [accel_y, accel_z, gyro_x] (REP 103 body axes, roll phi > 0 when
// the left side rises: phi = -(theta_s + (x2 - x1) / L)). The IMU channels and
// the tare convention need the readings kept as states (ReadingSettings):
// then 7 reading rows follow the 8 dynamic states and H selects them.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "pc_ekf/model/mechanical_model.h"
#include "pc_ekf/model/road_input.h"
#include "pc_ekf/model/suspension_laws.h"

namespace pc_ekf {

// The description of model.type roll_plane: parameter table (names, units,
// defaults, domains), settings, channels u1 u2 v1 v2, contacts, joints.
const ModelDescription& rollPlaneDescription();

// A typed copy of one roll-plane parameter vector plus the laws, for the
// static equilibrium and for tests. Field order and defaults come from
// rollPlaneDescription(): a default VehicleParameters holds the table's
// defaults.
struct VehicleParameters {
  VehicleParameters();
  double bar_mass{};
  double unsprung_mass[2]{};
  double damping[2]{};
  double spring_linear[2]{};
  double spring_cubic[2]{};
  double bar_length{};
  double bar_inertia{};
  double tyre_stiffness[2]{};
  double gravity{};
  double added_mass{};
  double added_mass_position{};
  double imu_position{};  // from the left end
  DamperLaw damper = DamperLaw::kTanh;
  double damper_tanh_scale{};  // F_C = c * scale * tanh(rate * v)
  double damper_tanh_rate{};

  Eigen::VectorXd toVector() const;
  static VehicleParameters fromVector(const Eigen::Ref<const Eigen::VectorXd>& v,
                                      const VehicleParameters& laws);
  static VehicleParameters from(const ModelParameters& m);
  ModelParameters toModelParameters() const;
};

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

struct RollPlaneReadings;

class RollPlaneModel : public MechanicalModel {
 public:
  // road: two contacts (left, right), else std::invalid_argument.
  RollPlaneModel(const VehicleParameters& nominal, std::shared_ptr<const ContactRoad> road,
                 ReadingSettings readings = {});

  const ModelDescription& description() const override { return rollPlaneDescription(); }
  const Eigen::VectorXd& nominalParameters() const override { return nominal_vector_; }
  std::string invalidReason(const Eigen::Ref<const Eigen::VectorXd>& params) const override;
  const Eigen::MatrixXd& observationMatrix() const override { return h_; }
  std::unique_ptr<ModelBatch> prepare(const Eigen::MatrixXd& params) const override;
  std::vector<double> breakpoints(double t0, double t1) const override;

  const std::vector<std::string>& stateNames() const override { return state_names_; }
  int readingCount() const override { return readings_.as_states ? 7 : 0; }
  bool channelModelled(int channel) const override {
    return readings_.as_states || channel < kSuspensionChannels;
  }
  ZeroConvention zero() const override { return readings_.zero; }
  static constexpr int kSuspensionChannels = 4;

  const VehicleParameters& nominal() const { return nominal_; }
  const ContactRoad& road() const { return *road_; }
  const ContactRoad* contactRoad() const override { return road_.get(); }

 private:
  std::unique_ptr<RollPlaneReadings> readingConstants(
      const std::vector<VehicleParameters>& points,
      const std::vector<StaticEquilibrium>& equilibria) const;

  VehicleParameters nominal_;
  ReadingSettings readings_;
  std::vector<std::string> state_names_;
  Eigen::VectorXd nominal_vector_;
  Eigen::MatrixXd h_;
  std::shared_ptr<const ContactRoad> road_;
};

}  // namespace pc_ekf
