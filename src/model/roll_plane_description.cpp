// The roll-plane model's description (docs/method.md §1): its parameter
// table, settings, channels, contacts and joints, and the binding of each
// table entry to its RollPlaneFields field. The only place that names them.
#include <limits>
#include <stdexcept>

#include "pc_ekf/model/field_table.h"
#include "pc_ekf/model/roll_plane_model.h"

namespace pc_ekf {
namespace {

// Any value at a point, >= 0 when configured.
ParameterDomain configuredNonNegative() {
  ParameterDomain d = anyValue();
  d.config_lower = 0.0;
  return d;
}

// Strictly positive unless said; the added mass may go negative at a point as
// long as the total mass and the combined inertia stay positive (model rule).
FieldTable<RollPlaneFields> parameterFields() {
  return FieldTable<RollPlaneFields>({
      {{"bar_mass", "kg", 580.0, positive(), "mass m of the bar (body)"}, PC_EKF_FIELD(bar_mass)},
      {{"unsprung_mass_left", "kg", 36.26, positive(), "unsprung mass m_t, left"},
       PC_EKF_FIELD(unsprung_mass[0])},
      {{"unsprung_mass_right", "kg", 36.26, positive(), "unsprung mass m_t, right"},
       PC_EKF_FIELD(unsprung_mass[1])},
      {{"damping_left", "N s/m", 710.70, nonNegative(), "damping c, left"},
       PC_EKF_FIELD(damping[0])},
      {{"damping_right", "N s/m", 710.70, nonNegative(), "damping c, right"},
       PC_EKF_FIELD(damping[1])},
      {{"spring_linear_left", "N/m", 19357.2, positive(), "linear spring stiffness k, left"},
       PC_EKF_FIELD(spring_linear[0])},
      {{"spring_linear_right", "N/m", 19357.2, positive(), "linear spring stiffness k, right"},
       PC_EKF_FIELD(spring_linear[1])},
      {{"spring_cubic_left", "N/m^3", 100000.0, nonNegative(), "cubic spring stiffness k3, left"},
       PC_EKF_FIELD(spring_cubic[0])},
      {{"spring_cubic_right", "N/m^3", 100000.0, nonNegative(), "cubic spring stiffness k3, right"},
       PC_EKF_FIELD(spring_cubic[1])},
      {{"bar_length", "m", 1.524, positive(),
        "length L of the bar: the wheel track (the rates act at the wheels)"},
       PC_EKF_FIELD(bar_length)},
      {{"bar_inertia", "kg m^2", 63.3316, positive(), "inertia I of the bar about its middle"},
       PC_EKF_FIELD(bar_inertia)},
      {{"tyre_stiffness_left", "N/m", 96319.76, positive(), "tyre stiffness k_t, left"},
       PC_EKF_FIELD(tyre_stiffness[0])},
      {{"tyre_stiffness_right", "N/m", 96319.76, positive(), "tyre stiffness k_t, right"},
       PC_EKF_FIELD(tyre_stiffness[1])},
      {{"gravity", "m/s^2", 9.81, positive(), "gravitational acceleration g"},
       PC_EKF_FIELD(gravity)},
      {{"added_mass", "kg", 200.0, configuredNonNegative(),
        "point load M on the bar (a point: total mass and inertia > 0)"},
       PC_EKF_FIELD(added_mass)},
      {{"added_mass_position", "m", 0.762, withinSumOf({"bar_length"}),
        "position d_CG of M from the left end"},
       PC_EKF_FIELD(added_mass_position)},
      {{"imu_position", "m", 0.762, withinSumOf({"bar_length"}),
        "IMU mount from the left end (not configured: midway between the mounts)",
        "bar_length", 0.5},
       PC_EKF_FIELD(imu_position)},
      {{"body_cg_height", "m", 0.0, anyValue(),
        "h_b: the empty body's centre of mass above the mount plane (the roll axis)"},
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
      {{"anti_roll_bar", "N/m", 0.0, nonNegative(),
        "k_a: the anti-roll bar's force at each end per metre of travel difference"},
       PC_EKF_FIELD(anti_roll_bar)},
      {{"body_cg_offset", "m", 0.0, anyValue(),
        "e_b: the empty body's centre of mass left of the middle of the mounts (REP 103 y; "
        "it sits at L/2 - e_b from the left end)"},
       PC_EKF_FIELD(body_cg_offset)},
  });
}

FieldTable<RollPlaneFields> settingFields() {
  return FieldTable<RollPlaneFields>({
      {{"damper_tanh_scale", "m/s", 0.2, positive(), "tanh damper: F_C = c scale tanh(rate v)"},
       PC_EKF_FIELD(damper_tanh_scale)},
      {{"damper_tanh_rate", "s/m", 10.0, positive(), "tanh damper: rate"},
       PC_EKF_FIELD(damper_tanh_rate)},
  });
}
const ModelFields<RollPlaneFields>& fields() {
  static const ModelFields<RollPlaneFields> f(parameterFields(), settingFields());
  return f;
}

}  // namespace

const std::vector<std::string>& rollPlaneChannels() {
  static const std::vector<std::string> names{"u1",     "u2",      "v1",    "v2",    "accel_y",
                                              "accel_z", "gyro_x", "speed", "gyro_z"};
  return names;
}

const ModelDescription& rollPlaneDescription() {
  const std::vector<std::string>& ch = rollPlaneChannels();
  static const ModelDescription d({
      "roll_plane",
      "The paper's 4-DOF roll-plane bar on two suspensions, left (1) and right (2) "
      "(docs/method.md §1).",
      fields().parameters().table(),
      fields().settings().table(),
      {damperChoiceWithTable()},
      {"x1", "x2", "xr1", "xr2", "x1dot", "x2dot", "xr1dot", "xr2dot"},
      {{ch[0], "m", "suspension extension x1 - xr1, left"},
       {ch[1], "m", "suspension extension x2 - xr2, right"},
       {ch[2], "m/s", "suspension extension rate, left"},
       {ch[3], "m/s", "suspension extension rate, right"},
       {ch[4], "m/s^2",
        "IMU specific force along body y (left): (g + a) sin(phi) + a_y cos(phi) - z_I phi''",
        false},
       {ch[5], "m/s^2",
        "IMU specific force along body z (up): (g + a) cos(phi) - a_y phi - z_I phi'^2", false},
       {ch[6], "rad/s", "IMU roll rate (phi > 0: left side up)", false},
       {ch[7], "m/s", "forward speed over ground (the drive's horizontal motion)", false},
       {ch[8], "rad/s", "yaw rate, positive turning left: a_y / speed", false}},
      {{"left", "y1", "left tyre"}, {"right", "y2", "right tyre"}},
      {{"left_suspension", "left", ch[0], ch[2]}, {"right_suspension", "right", ch[1], ch[3]}},
  });
  return d;
}

const RollPlaneFields<int>& rollPlaneRows() { return fields().rows(); }

VehicleParameters::VehicleParameters() { fields().setDefaults(rollPlaneDescription(), *this); }

Eigen::VectorXd VehicleParameters::toVector() const { return fields().parameters().read(*this); }

VehicleParameters VehicleParameters::fromVector(const Eigen::Ref<const Eigen::VectorXd>& v,
                                                const VehicleParameters& laws) {
  return fields().fromVector(rollPlaneDescription(), v, laws, "VehicleParameters::fromVector");
}

VehicleParameters VehicleParameters::from(const ModelParameters& m) {
  VehicleParameters p =
      fields().from<VehicleParameters>(rollPlaneDescription(), m, "VehicleParameters::from");
  rollPlaneDamperCurves(m, p.damper_curve);
  return p;
}

ModelParameters VehicleParameters::toModelParameters() const {
  ModelParameters m = fields().toModelParameters(*this);
  if (damper == DamperLaw::kTable) {
    for (int i = 0; i < 2; ++i) {
      const DamperCurve& c = damper_curve[i];
      Eigen::MatrixXd points(2, static_cast<Eigen::Index>(c.velocity().size()));
      for (std::size_t j = 0; j < c.velocity().size(); ++j) {
        points(0, static_cast<Eigen::Index>(j)) = c.velocity()[j];
        points(1, static_cast<Eigen::Index>(j)) = c.force()[j];
      }
      m.tables[kDamperTableNames[i]] = points;
    }
  }
  return m;
}

const char* const kDamperTableNames[2] = {"damper_table_left", "damper_table_right"};

void rollPlaneDamperCurves(const ModelParameters& m, DamperCurve out[2]) {
  if (damperLaw(m.choice(rollPlaneDescription(), "damper")) != DamperLaw::kTable) {
    out[0] = out[1] = DamperCurve();
    return;
  }
  for (int i = 0; i < 2; ++i) {
    const auto it = m.tables.find(kDamperTableNames[i]);
    if (it == m.tables.end()) {
      throw std::invalid_argument(std::string("roll plane: damper table but no ") +
                                  kDamperTableNames[i]);
    }
    out[i] = DamperCurve(it->second, std::string("roll plane: ") + kDamperTableNames[i]);
  }
}

}  // namespace pc_ekf
