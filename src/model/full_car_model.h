// Full-car 7-DOF ride model: a rigid body (heave, pitch, roll) on four
// corners, each an unsprung mass on a tyre, with an added point mass M.
//
// Axes: x forward, y left, z up; heights are deviations, up positive.
//   theta > 0 raises the front: it is minus the right-handed pitch about a
//     left-pointing y axis.
//   phi > 0 raises the left side: right-handed roll about x.
// Small angles: corner i at (x_i, y_i) from the body's centre O is at height
// z + x_i theta + y_i phi. Corners in the order front_left, front_right,
// rear_left, rear_right at (a, w/2), (a, -w/2), (-b, w/2), (-b, -w/2).
//
// State (deviations from the static equilibrium):
//   [z, theta, phi, zu_fl, zu_fr, zu_rl, zu_rr, and their rates] (14)
// Channels: u_fl u_fr u_rl u_rr (suspension extension z_i - zu_i) and their
// rates v_fl .. v_rr, then the IMU's accel_y accel_z gyro_x gyro_y (REP 103
// body axes; its pitch, nose down > 0, is -theta), then accel_x and the
// drive's speed and gyro_z (the road's horizontal motion). Heights above the
// mount plane, anti-roll bars and the horizontal accelerations a_x, a_y:
// docs/models.md (all 0: the 7-DOF ride model; q is then that of O' below O,
// corners at (x_i, y_i, 0) from it). The IMU channels and the
// tare convention need the readings kept as states (ReadingSettings): then
// 15 reading rows follow the 14 dynamic states, each corner's extension with
// the point's own geometry, and H selects them. Otherwise: The observation matrix is fixed, so it uses the nominal
// geometry (a, b, w): for a point whose a, b or w differ from the nominal,
// H y is not that point's own extension once the body pitches or rolls.
#pragma once

#include <cstdint>

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "pc_ekf/model/mechanical_model.h"
#include "pc_ekf/model/road_input.h"
#include "pc_ekf/model/suspension_laws.h"

namespace pc_ekf {

// The description of model.type full_car: parameter table, settings,
// channels u_fl .. v_rr, contacts front_left .. rear_right, joints.
const ModelDescription& fullCarDescription();

// The full car's fields, declared once over the element type (field_table.h):
// the parameters, in the order of fullCarDescription()'s table, then the
// settings. FullCarFields<int>: each field's row in its table. Unsprung
// masses, springs and dampers are per axle.
template <class T>
struct FullCarFields {
  T body_mass{};            // m_s, kg
  T roll_inertia{};         // I_xx about O, kg m^2
  T pitch_inertia{};        // I_yy about O, kg m^2
  T front_axle_distance{};  // a, O to the front axle, m
  T rear_axle_distance{};   // b, O to the rear axle, m
  T track_width{};          // w, m
  T unsprung_mass[2]{};     // front, rear
  T spring_linear[2]{};     // N/m
  T spring_cubic[2]{};      // N/m^3
  T damping[2]{};           // N s/m
  T tyre_stiffness{};       // N/m, all four
  T gravity{};
  T added_mass{};    // M, kg
  T added_mass_x{};  // forward of the rear axle, m
  T added_mass_y{};  // left of the right wheels' line, m
  T imu_x{}, imu_y{};  // IMU mount relative to O, m
  // Heights above the mount plane (the pitch and roll axes) and the anti-roll
  // bars (docs/models.md): all 0 is the 7-DOF ride model without heights.
  T body_cg_height{};     // h_b: O above O', the point of the mount plane below it
  T added_mass_height{};  // h_M
  T mount_height{};       // h_P, the mount plane above the ground
  T wheel_radius{};       // r_w
  T imu_height{};         // z_I
  T anti_roll_bar[2]{};   // k_a, front and rear, N/m of travel difference
  // Settings: F_C = c * scale * tanh(rate * v), or F_C = c v.
  T damper_tanh_scale{};  // m/s
  T damper_tanh_rate{};   // s/m
};
// A parameter's row in the parameter vector, a setting's in the settings.
const FullCarFields<int>& fullCarRows();

// Positions relative to the body's centre O from a (front_axle_distance), b
// (rear_axle_distance) and w (track_width): those of FullCarParameters and
// of FullCarColumn.
namespace full_car_geometry {
inline double cornerX(int c, double a, double b) { return c < 2 ? a : -b; }
inline double cornerY(int c, double w) { return c % 2 == 0 ? 0.5 * w : -0.5 * w; }
inline double addedMassX(double added_mass_x, double b) { return added_mass_x - b; }
inline double addedMassY(double added_mass_y, double w) { return added_mass_y - 0.5 * w; }
}  // namespace full_car_geometry

// One point's values where they are, in its column of the parameter matrix
// (read by fullCarRows()): how the model reads a point, with no typed copy.
class FullCarColumn {
 public:
  explicit FullCarColumn(const double* values) : v_(values), at_(fullCarRows()) {}
  // A field's value, e.g. p[p.at().spring_linear[0]].
  double operator[](int row) const { return v_[row]; }
  const FullCarFields<int>& at() const { return at_; }
  double addedMassX() const {
    return full_car_geometry::addedMassX(v_[at_.added_mass_x], v_[at_.rear_axle_distance]);
  }
  double addedMassY() const {
    return full_car_geometry::addedMassY(v_[at_.added_mass_y], v_[at_.track_width]);
  }
  double cornerX(int c) const {
    return full_car_geometry::cornerX(c, v_[at_.front_axle_distance], v_[at_.rear_axle_distance]);
  }
  double cornerY(int c) const { return full_car_geometry::cornerY(c, v_[at_.track_width]); }
  // The body's mass matrix on (z, theta, phi) with M, a point mass at
  // (x_M, y_M) at the height of O (it moves with z + x_M theta + y_M phi).
  Eigen::Matrix3d bodyMass() const;

 private:
  const double* v_;
  const FullCarFields<int>& at_;
};

// A typed copy of one full-car parameter vector plus the laws. A default
// FullCarParameters holds the table's defaults.
struct FullCarParameters : FullCarFields<double> {
  FullCarParameters();
  DamperLaw damper = DamperLaw::kTanh;  // not in the vector

  double wheelbase() const { return front_axle_distance + rear_axle_distance; }
  // Position of M relative to O.
  double addedMassX() const {
    return full_car_geometry::addedMassX(added_mass_x, rear_axle_distance);
  }
  double addedMassY() const { return full_car_geometry::addedMassY(added_mass_y, track_width); }
  // Corner c (0 fl, 1 fr, 2 rl, 3 rr) relative to O.
  double cornerX(int c) const {
    return full_car_geometry::cornerX(c, front_axle_distance, rear_axle_distance);
  }
  double cornerY(int c) const { return full_car_geometry::cornerY(c, track_width); }
  // Axle (0 front, 1 rear) of corner c.
  static int axle(int c) { return c / 2; }

  Eigen::VectorXd toVector() const;
  // Damper law and tanh constants come from `laws`.
  static FullCarParameters fromVector(const Eigen::Ref<const Eigen::VectorXd>& v,
                                      const FullCarParameters& laws);
  static FullCarParameters from(const ModelParameters& m);
  ModelParameters toModelParameters() const;
};

const std::vector<std::string>& fullCarParameterNames();

// fullCarDescription().parameters().names() and .violation(): "" when
// admissible by the table's domains alone; FullCarModel::invalidReason also
// requires the equilibrium to converge.
std::string fullCarParameterRuleViolation(const Eigen::Ref<const Eigen::VectorXd>& params);

// Static equilibrium, heights from the unloaded geometry (springs at free
// length, tyres just touching).
struct FullCarEquilibrium {
  double heave = 0.0, pitch = 0.0, roll = 0.0;  // z_s, theta_s, phi_s of O
  double wheel_height[4] = {0, 0, 0, 0};        // zu_i (= -tyre compression)
  double spring_compression[4] = {0, 0, 0, 0};  // delta_i = zu_i - corner height
  double load[4] = {0, 0, 0, 0};                // F_K,i(delta_i), N
  int iterations = 0;                           // Newton steps after the linear start
};
// Newton from the linear-spring solution; throws std::runtime_error when it
// fails to converge.
FullCarEquilibrium solveFullCarEquilibrium(const FullCarParameters& p);
FullCarEquilibrium solveFullCarEquilibrium(const FullCarColumn& p);
// Newton from another point's solution (a filter's steps from one point);
// the same equilibrium to round-off. When Newton fails from there, the
// solve from the linear springs decides (and throws as it throws).
FullCarEquilibrium solveFullCarEquilibriumFrom(const FullCarColumn& p,
                                               const FullCarEquilibrium& start);
// The numbers the solve reads (corner positions, springs, unsprung weights,
// tyre, loads, bars, the elevated moment): columns with equal keys have the
// same equilibrium bit for bit (a damper or an inertia does not enter).
using FullCarEquilibriumKey = std::array<double, 30>;
FullCarEquilibriumKey fullCarEquilibriumKey(const FullCarColumn& p);
std::vector<FullCarEquilibrium> solveFullCarEquilibria(const std::vector<FullCarParameters>& ps);

struct FullCarReadings;

class FullCarModel : public MechanicalModel {
 public:
  // road: 4 contacts (front_left, front_right, rear_left, rear_right), else
  // std::invalid_argument.
  FullCarModel(ModelParameters nominal, std::shared_ptr<const ContactRoad> road,
               ReadingSettings readings = {});
  FullCarModel(const FullCarParameters& nominal, std::shared_ptr<const ContactRoad> road,
               ReadingSettings readings = {})
      : FullCarModel(nominal.toModelParameters(), std::move(road), readings) {}

  const ModelDescription& description() const override { return fullCarDescription(); }
  const Eigen::VectorXd& nominalParameters() const override { return nominal_vector_; }
  std::string invalidReason(const Eigen::Ref<const Eigen::VectorXd>& params) const override;
  const Eigen::MatrixXd& observationMatrix() const override { return h_; }
  std::unique_ptr<ModelBatch> prepare(const Eigen::MatrixXd& params) const override;
  std::vector<double> breakpoints(double t0, double t1) const override;

  const std::vector<std::string>& stateNames() const override { return state_names_; }
  int readingCount() const override { return readings_.as_states ? kChannels : 0; }
  bool channelModelled(int channel) const override {
    return readings_.as_states || channel < kSuspensionChannels;
  }
  ZeroConvention zero() const override { return readings_.zero; }
  static constexpr int kSuspensionChannels = 8;
  // u_fl .. v_rr, accel_y accel_z gyro_x gyro_y, accel_x speed gyro_z.
  static constexpr int kChannels = 15;

  const FullCarParameters& nominal() const { return nominal_; }
  const ContactRoad& road() const { return *road_; }
  const ContactRoad* contactRoad() const override { return road_.get(); }

  // The equilibrium at params (a Newton solve), memoised per thread: the
  // forecast asks invalidReason for each point and then prepares the same
  // points on the same thread, so each point is solved once, not twice (the
  // road-free model asks it too). Throws what solveFullCarEquilibrium throws.
  FullCarEquilibrium equilibrium(const Eigen::Ref<const Eigen::VectorXd>& params) const;

 private:
  std::unique_ptr<FullCarReadings> readingConstants(const Eigen::MatrixXd& params) const;

  FullCarParameters nominal_;  // the laws and the nominal geometry of H
  ReadingSettings readings_;
  std::vector<std::string> state_names_;
  Eigen::VectorXd nominal_vector_;
  Eigen::MatrixXd h_;
  std::shared_ptr<const ContactRoad> road_;
};

}  // namespace pc_ekf
