// The full-car model's description (docs/method.md §2): its parameter table,
// settings, channels, contacts and joints, and the binding of each table
// entry to its FullCarFields field. The only place that names them.
#include <limits>
#include <stdexcept>

#include "pc_ekf/model/field_table.h"
#include "pc_ekf/model/full_car_model.h"

namespace pc_ekf {
namespace {

// Unsprung masses, springs and dampers are per axle (both corners alike).
FieldTable<FullCarFields> parameterFields() {
  return FieldTable<FullCarFields>({
      {{"body_mass", "kg", 1200.0, positive(), "sprung mass m_s"}, PC_EKF_FIELD(body_mass)},
      {{"roll_inertia", "kg m^2", 400.0, positive(), "roll inertia I_xx about O"},
       PC_EKF_FIELD(roll_inertia)},
      {{"pitch_inertia", "kg m^2", 1600.0, positive(), "pitch inertia I_yy about O"},
       PC_EKF_FIELD(pitch_inertia)},
      {{"front_axle_distance", "m", 1.1, positive(), "a: O to the front axle"},
       PC_EKF_FIELD(front_axle_distance)},
      {{"rear_axle_distance", "m", 1.5, positive(), "b: O to the rear axle"},
       PC_EKF_FIELD(rear_axle_distance)},
      {{"track_width", "m", 1.5, positive(), "w: between the left and right wheels"},
       PC_EKF_FIELD(track_width)},
      {{"unsprung_mass_front", "kg", 40.0, positive(), "unsprung mass per front corner"},
       PC_EKF_FIELD(unsprung_mass[0])},
      {{"unsprung_mass_rear", "kg", 35.0, positive(), "unsprung mass per rear corner"},
       PC_EKF_FIELD(unsprung_mass[1])},
      {{"spring_linear_front", "N/m", 20000.0, positive(), "linear spring stiffness k, front"},
       PC_EKF_FIELD(spring_linear[0])},
      {{"spring_linear_rear", "N/m", 22000.0, positive(), "linear spring stiffness k, rear"},
       PC_EKF_FIELD(spring_linear[1])},
      {{"spring_cubic_front", "N/m^3", 100000.0, nonNegative(), "cubic spring stiffness k3, front"},
       PC_EKF_FIELD(spring_cubic[0])},
      {{"spring_cubic_rear", "N/m^3", 100000.0, nonNegative(), "cubic spring stiffness k3, rear"},
       PC_EKF_FIELD(spring_cubic[1])},
      {{"damping_front", "N s/m", 1500.0, nonNegative(), "damping c, front"},
       PC_EKF_FIELD(damping[0])},
      {{"damping_rear", "N s/m", 1400.0, nonNegative(), "damping c, rear"},
       PC_EKF_FIELD(damping[1])},
      {{"tyre_stiffness", "N/m", 200000.0, positive(), "tyre stiffness k_t, all four"},
       PC_EKF_FIELD(tyre_stiffness)},
      {{"gravity", "m/s^2", 9.81, positive(), "gravitational acceleration g"},
       PC_EKF_FIELD(gravity)},
      {{"added_mass", "kg", 200.0, nonNegative(), "point mass M at the height of O"},
       PC_EKF_FIELD(added_mass)},
      {{"added_mass_x", "m", 1.3, withinSumOf({"front_axle_distance", "rear_axle_distance"}),
        "position of M forward of the rear axle"},
       PC_EKF_FIELD(added_mass_x)},
      {{"added_mass_y", "m", 0.75, withinSumOf({"track_width"}),
        "position of M left of the right wheels' line"},
       PC_EKF_FIELD(added_mass_y)},
      {{"imu_x", "m", 0.0, anyValue(), "IMU mount forward of the body's centre O (default: at O)"},
       PC_EKF_FIELD(imu_x)},
      {{"imu_y", "m", 0.0, anyValue(), "IMU mount left of the body's centre O (default: at O)"},
       PC_EKF_FIELD(imu_y)},
      {{"body_cg_height", "m", 0.0, anyValue(),
        "h_b: the empty body's centre of mass above the mount plane (O above O')"},
       PC_EKF_FIELD(body_cg_height)},
      {{"added_mass_height", "m", 0.0, anyValue(), "h_M: the load M above the mount plane"},
       PC_EKF_FIELD(added_mass_height)},
      {{"mount_height", "m", 0.0, nonNegative(),
        "h_P: the mount plane above the ground, vehicle at rest"},
       PC_EKF_FIELD(mount_height)},
      {{"wheel_radius", "m", 0.0, nonNegative(), "r_w: the axles' height above the ground"},
       PC_EKF_FIELD(wheel_radius)},
      {{"imu_height", "m", 0.0, anyValue(), "z_I: the IMU above the mount plane"},
       PC_EKF_FIELD(imu_height)},
      {{"anti_roll_bar_front", "N/m", 0.0, nonNegative(),
        "k_a of the front axle: force at each end per metre of travel difference"},
       PC_EKF_FIELD(anti_roll_bar[0])},
      {{"anti_roll_bar_rear", "N/m", 0.0, nonNegative(),
        "k_a of the rear axle: force at each end per metre of travel difference"},
       PC_EKF_FIELD(anti_roll_bar[1])},
  });
}

FieldTable<FullCarFields> settingFields() {
  return FieldTable<FullCarFields>({
      {{"damper_tanh_scale", "m/s", 1.0, positive(), "tanh damper: F_C = c scale tanh(rate v)"},
       PC_EKF_FIELD(damper_tanh_scale)},
      {{"damper_tanh_rate", "s/m", 1.0, positive(), "tanh damper: rate"},
       PC_EKF_FIELD(damper_tanh_rate)},
  });
}
const ModelFields<FullCarFields>& fields() {
  static const ModelFields<FullCarFields> f(parameterFields(), settingFields());
  return f;
}

}  // namespace

const ModelDescription& fullCarDescription() {
  static const ModelDescription d({
      "full_car",
      "A 7-DOF full car: a rigid body (heave, pitch, roll) on four corners, each an "
      "unsprung mass on a tyre, with an added point mass (docs/method.md §2).",
      fields().parameters().table(),
      fields().settings().table(),
      {damperChoice()},
      {"z", "theta", "phi", "zu_fl", "zu_fr", "zu_rl", "zu_rr", "zdot", "thetadot", "phidot",
       "zudot_fl", "zudot_fr", "zudot_rl", "zudot_rr"},
      {{"u_fl", "m", "suspension extension, front left"},
       {"u_fr", "m", "suspension extension, front right"},
       {"u_rl", "m", "suspension extension, rear left"},
       {"u_rr", "m", "suspension extension, rear right"},
       {"v_fl", "m/s", "extension rate, front left"},
       {"v_fr", "m/s", "extension rate, front right"},
       {"v_rl", "m/s", "extension rate, rear left"},
       {"v_rr", "m/s", "extension rate, rear right"},
       {"accel_y", "m/s^2",
        "IMU specific force along body y (left): (g + a) cos(theta) sin(phi) + a_y cos(phi) - "
        "z_I phi''",
        false},
       {"accel_z", "m/s^2",
        "IMU specific force along body z (up): (g + a) cos(theta) cos(phi) - a_y phi - a_x theta "
        "- z_I (phi'^2 + theta'^2)",
        false},
       {"gyro_x", "rad/s", "IMU roll rate (phi > 0: left side up)", false},
       {"gyro_y", "rad/s", "IMU pitch rate (REP 103: nose down > 0, i.e. -thetadot)", false},
       {"accel_x", "m/s^2",
        "IMU specific force along body x (forward): a_x + (g + z'') theta - z_I theta'' - "
        "imu_x theta'^2",
        false},
       {"speed", "m/s", "forward speed over ground (the drive's horizontal motion)", false},
       {"gyro_z", "rad/s", "yaw rate, positive turning left: a_y / speed", false}},
      {{"front_left", "", "front left tyre"},
       {"front_right", "", "front right tyre"},
       {"rear_left", "", "rear left tyre"},
       {"rear_right", "", "rear right tyre"}},
      {{"front_left_suspension", "front_left", "u_fl", "v_fl"},
       {"front_right_suspension", "front_right", "u_fr", "v_fr"},
       {"rear_left_suspension", "rear_left", "u_rl", "v_rl"},
       {"rear_right_suspension", "rear_right", "u_rr", "v_rr"}},
  });
  return d;
}

const FullCarFields<int>& fullCarRows() { return fields().rows(); }

FullCarParameters::FullCarParameters() { fields().setDefaults(fullCarDescription(), *this); }

Eigen::VectorXd FullCarParameters::toVector() const { return fields().parameters().read(*this); }

FullCarParameters FullCarParameters::fromVector(const Eigen::Ref<const Eigen::VectorXd>& v,
                                                const FullCarParameters& laws) {
  return fields().fromVector(fullCarDescription(), v, laws, "FullCarParameters::fromVector");
}

FullCarParameters FullCarParameters::from(const ModelParameters& m) {
  return fields().from<FullCarParameters>(fullCarDescription(), m, "FullCarParameters::from");
}

ModelParameters FullCarParameters::toModelParameters() const {
  return fields().toModelParameters(*this);
}

const std::vector<std::string>& fullCarParameterNames() {
  return fullCarDescription().parameters().names();
}

std::string fullCarParameterRuleViolation(const Eigen::Ref<const Eigen::VectorXd>& params) {
  return fullCarDescription().parameters().violation(params);
}

}  // namespace pc_ekf
