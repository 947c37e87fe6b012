// The nonlinear 4-DOF roll-plane vehicle model of docs/method.md §1.
//
// State (deviations from the static equilibrium, up positive):
//   [x1, x2, xr1, xr2, x1dot, x2dot, xr1dot, xr2dot]
// Channels: [u1, u2, v1, v2], u_i = x_i - xr_i, v_i = xidot - xridot, then
// the IMU's [accel_y, accel_z, gyro_x] (REP 103 body axes, roll phi > 0 when
// the left side rises: phi = -(theta_s + (x2 - x1) / L)), then the drive's
// [speed, gyro_z] (the road's horizontal motion). The IMU channels, speed,
// gyro_z and the tare convention need the readings kept as states
// (ReadingSettings): then 9 reading rows follow the 8 dynamic states and H
// selects them.
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

// The roll plane's channel names, in the channels' order (RollPlaneModel's
// channel indices): u1 u2 v1 v2 accel_y accel_z gyro_x speed gyro_z. The one
// list the description, the model type and the road-free model read.
const std::vector<std::string>& rollPlaneChannels();

// The roll plane's fields, declared once over the element type (field_table.h):
// the parameters, in the order of rollPlaneDescription()'s table, then the
// settings. RollPlaneFields<int>: each field's row in its table.
template <class T>
struct RollPlaneFields {
  T bar_mass{};
  T unsprung_mass[2]{};
  T damping[2]{};
  T spring_linear[2]{};
  T spring_cubic[2]{};
  T bar_length{};
  T bar_inertia{};
  T tyre_stiffness[2]{};
  T gravity{};
  T added_mass{};
  T added_mass_position{};
  T imu_position{};  // from the left end
  // Heights above the mount plane (the roll axis) and the anti-roll bar
  // (docs/models.md): all 0 is the paper's model.
  T body_cg_height{};     // h_b
  T added_mass_height{};  // h_M
  T mount_height{};       // h_P, the mount plane above the ground
  T wheel_radius{};       // r_w
  T imu_height{};         // z_I
  T anti_roll_bar{};      // k_a, N/m of travel difference
  T body_cg_offset{};     // e_b: the empty body's centre left of the mounts' middle
  // Settings.
  T damper_tanh_scale{};  // F_C = c * scale * tanh(rate * v)
  T damper_tanh_rate{};
};
// The ModelParameters::tables names of the damper curves, left and right.
extern const char* const kDamperTableNames[2];
// The curves of `m` when its damper law is table (std::invalid_argument when
// one is missing or bad), else empty curves.
void rollPlaneDamperCurves(const ModelParameters& m, DamperCurve out[2]);

// Where prepare() and the model's rules read each value: a parameter's row
// in the parameter vector, a setting's in the settings.
const RollPlaneFields<int>& rollPlaneRows();

// A typed copy of one roll-plane parameter vector plus the laws, for the
// static equilibrium summary and for tests (the model itself reads its
// parameter matrix by rollPlaneRows()). A default VehicleParameters holds the
// table's defaults.
struct VehicleParameters : RollPlaneFields<double> {
  VehicleParameters();
  DamperLaw damper = DamperLaw::kTanh;
  // damper == kTable: the measured curves at the wheels, left and right
  // (ModelParameters::tables damper_table_left, damper_table_right).
  DamperCurve damper_curve[2];

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
// The same for many parameter vectors at once, the columns of `params` (each
// result identical to the single solve; the Newton iterations of all springs
// advance together, which is faster).
std::vector<StaticEquilibrium> solveStaticEquilibria(const Eigen::MatrixXd& params);
// "" when the point (heights above the mount plane) has a stable static
// equilibrium, else why not: the tyres' or the springs' roll stiffness does
// not carry the elevated masses' moment g S (docs/models.md). Closed form
// except near that edge, where it solves the point.
std::string rollPlaneEquilibriumRefusal(const Eigen::Ref<const Eigen::VectorXd>& params);

struct RollPlaneReadings;

class RollPlaneModel : public MechanicalModel {
 public:
  // road: two contacts (left, right), else std::invalid_argument. nominal:
  // the parameter vector, settings and damper choice of the description.
  RollPlaneModel(ModelParameters nominal, std::shared_ptr<const ContactRoad> road,
                 ReadingSettings readings = {});
  RollPlaneModel(const VehicleParameters& nominal, std::shared_ptr<const ContactRoad> road,
                 ReadingSettings readings = {})
      : RollPlaneModel(nominal.toModelParameters(), std::move(road), readings) {}

  const ModelDescription& description() const override { return rollPlaneDescription(); }
  const Eigen::VectorXd& nominalParameters() const override { return nominal_.values; }
  std::string invalidReason(const Eigen::Ref<const Eigen::VectorXd>& params) const override;
  const Eigen::MatrixXd& observationMatrix() const override { return h_; }
  std::unique_ptr<ModelBatch> prepare(const Eigen::MatrixXd& params) const override;
  std::vector<double> breakpoints(double t0, double t1) const override;
  // x_i and xr_i keep their absolute heights (the equilibria's mount heights
  // and tyre compressions); the readings kept as states follow at the next
  // integration's end.
  void carryOver(const Eigen::VectorXd& from, const Eigen::VectorXd& to,
                 Eigen::ArrayXXd& y) const override;

  const std::vector<std::string>& stateNames() const override { return state_names_; }
  int readingCount() const override { return readings_.as_states ? kChannels : 0; }
  bool channelModelled(int channel) const override {
    return readings_.as_states || channel < kSuspensionChannels;
  }
  ZeroConvention zero() const override { return readings_.zero; }
  static constexpr int kSuspensionChannels = 4;
  static constexpr int kChannels = 9;  // u1 u2 v1 v2 accel_y accel_z gyro_x speed gyro_z

  VehicleParameters nominal() const;  // a typed copy
  const ContactRoad& road() const { return *road_; }
  const ContactRoad* contactRoad() const override { return road_.get(); }

 private:
  std::unique_ptr<RollPlaneReadings> readingConstants(
      const Eigen::MatrixXd& params, const std::vector<StaticEquilibrium>& equilibria) const;

  ModelParameters nominal_;  // values: the nominal parameter vector
  DamperLaw damper_;
  double tanh_scale_, tanh_rate_;
  DamperCurve curve_[2];  // damper_ == kTable
  ReadingSettings readings_;
  std::vector<std::string> state_names_;
  Eigen::MatrixXd h_;
  std::shared_ptr<const ContactRoad> road_;
};

}  // namespace pc_ekf
