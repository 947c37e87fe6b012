// Full-car ride model: parameter checks and the batched right-hand side.
#include "pc_ekf/model/full_car_model.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <utility>

#include "pc_ekf/model/horizontal_motion.h"
#include "pc_ekf/model/smooth_functions.h"

namespace pc_ekf {

// What each point's readings need beyond its dynamics (readings as states).
struct FullCarReadings {
  Eigen::ArrayXXd corner_x, corner_y;  // 4 x Q, the point's own geometry
  Eigen::ArrayXXd travel_offset;       // 4 x Q, subtracted from u_i: 0 (rest); sag (tare)
  Eigen::ArrayXd imu_x, imu_y, gravity;
  Eigen::ArrayXd roll_static, pitch_static;  // phi_s, and REP 103 pitch -theta_s
  Eigen::ArrayXd rest_y, rest_z;              // static specific force (rest); 0 (tare)
  Eigen::ArrayXd rest_x;                      // accel_x at rest: g theta_s (rest); 0 (tare)
  Eigen::ArrayXd imu_height;                  // z_I
  // Heights, bars, an IMU height or a horizontal motion (docs/models.md): the
  // accelerations' and z_I terms in accel_y and accel_z (else today's bits).
  bool elevated = false;
};

namespace {

// A direct-mapped table of the thread's latest equilibria, keyed by the exact
// bits of what the solve reads (fullCarEquilibriumKey: a hit returns what the
// solve gave; with heights or bars it started from the thread's previous
// solve, so a stream's numbers follow from its order, the same on every run). Not by the whole parameter vector: the
// one-step filter's finite-difference Jacobian steps dampers, inertias and,
// at the empty vehicle (tare), the load's position, which leave it as it is.
struct EquilibriumMemo {
  struct Slot {
    bool used = false;
    FullCarEquilibriumKey key{};
    FullCarEquilibrium equilibrium;
    std::string error;  // the solve's failure, if it failed
  };
  static constexpr std::size_t kSlots = 1024;
  std::array<Slot, kSlots> slots;
  // The thread's last solves: with heights or bars, a miss near one of them
  // (every number the solve reads within 5 %: the filter's next step, its
  // next sample's point, the empty vehicle's at the next point for `tare`,
  // a few dozen solves later) starts Newton there. Without them the solve is always from the linear springs (their
  // numbers stay as they were, bit for bit).
  static constexpr std::size_t kRecent = 32;
  std::array<const Slot*, kRecent> recent{};
  std::size_t next_recent = 0;
  const Slot* near(const FullCarEquilibriumKey& key) const {
    if (key.back() == 0.0) return nullptr;
    for (std::size_t k = 0; k < kRecent; ++k) {
      const Slot* r = recent[(next_recent + kRecent - 1 - k) % kRecent];  // newest first
      if (r && r->error.empty() && r->key.back() != 0.0 && close(key, r->key)) return r;
    }
    return nullptr;
  }
  // The load's moments (g M x_M, g M y_M: 0 at the middle) on the scale of
  // the weight times a metre, every other number on its own.
  static bool close(const FullCarEquilibriumKey& a, const FullCarEquilibriumKey& b) {
    constexpr std::size_t kWeight = 25;
    // The weight first: the loaded and the empty vehicle part there.
    if (!(std::abs(a[kWeight] - b[kWeight]) <= 0.05 * std::abs(a[kWeight]))) return false;
    for (std::size_t i = 0; i < a.size(); ++i) {
      const double scale = (i == kWeight + 1 || i == kWeight + 2)
                               ? std::abs(a[kWeight])
                               : std::max(std::abs(a[i]), std::abs(b[i]));
      if (!(std::abs(a[i] - b[i]) <= 0.05 * scale)) return false;
    }
    return true;
  }
  void solved(const Slot* slot) {
    for (const Slot*& r : recent) {
      if (r == slot) r = nullptr;  // overwritten: its old key is gone
    }
    recent[next_recent] = slot;
    next_recent = (next_recent + 1) % kRecent;
  }

  static std::size_t slotOf(const FullCarEquilibriumKey& key) {
    std::uint64_t h = 1469598103934665603ull;  // FNV-1a over whole words, then mixed
    for (const double v : key) {
      std::uint64_t bits;
      std::memcpy(&bits, &v, sizeof bits);
      h = (h ^ bits) * 1099511628211ull;
      h ^= h >> 29;
    }
    return static_cast<std::size_t>(h % kSlots);
  }
};


// Per-point constants, one column per quantity (PointConstantTable).
struct PointConstants : PointConstantTable {
  enum Column {
    kX = 0,  // corner position relative to O, 4 each
    kY = 4,
    kK = 8,  // spring law about the static compression delta
    kK3 = 12,
    kThreeDelta = 16,
    kThreeDeltaSq = 20,
    kDamping = 24,  // c (linear) or c * tanh scale
    kInvUnsprung = 28,
    kTyre = 32,
    kInvBodyMass = 33,  // M_b^-1, row-major 3 x 3
    kCount = 42
  };
  explicit PointConstants(Eigen::Index q) : PointConstantTable(q, kCount) {}
};

// Raw column pointers (loop-invariant in the vectorised loop).
struct ConstantPointers {
  const double *x[4], *y[4], *k[4], *k3[4], *three_delta[4], *three_delta_sq[4], *damping[4],
      *inv_unsprung[4];
  const double* tyre;
  const double* inv_body_mass[9];
  explicit ConstantPointers(const PointConstants& c) {
    using C = PointConstants;
    for (int i = 0; i < 4; ++i) {
      x[i] = c.column(C::kX + i);
      y[i] = c.column(C::kY + i);
      k[i] = c.column(C::kK + i);
      k3[i] = c.column(C::kK3 + i);
      three_delta[i] = c.column(C::kThreeDelta + i);
      three_delta_sq[i] = c.column(C::kThreeDeltaSq + i);
      damping[i] = c.column(C::kDamping + i);
      inv_unsprung[i] = c.column(C::kInvUnsprung + i);
    }
    tyre = c.column(C::kTyre);
    for (int j = 0; j < 9; ++j) inv_body_mass[j] = c.column(C::kInvBodyMass + j);
  }
};

// One point q: state s[14] -> d[14] at stride `stride` (1: column-major
// states, Q: the transposed layout). Branch-free, so a loop over q vectorises.
template <DamperLaw law>
__attribute__((always_inline)) inline void pointDerivatives(const ConstantPointers& c,
                                                            Eigen::Index q, double tanh_rate,
                                                            const double road[4], const double* s,
                                                            double* d, Eigen::Index stride) {
  const auto at = [&](int i) { return s[i * stride]; };
  double f[4];
  double gen[3] = {0.0, 0.0, 0.0};  // generalised force on (z, theta, phi)
  for (int i = 0; i < 4; ++i) {
    const double x = c.x[i][q], y = c.y[i][q];
    const double u = at(0) + x * at(1) + y * at(2) - at(3 + i);
    const double v = at(7) + x * at(8) + y * at(9) - at(10 + i);
    const double damper = damperForce<law>(c.damping[i][q], tanh_rate, v);
    const double spring =
        springIncrement(u, c.k[i][q], c.k3[i][q], c.three_delta[i][q], c.three_delta_sq[i][q]);
    f[i] = -spring - damper;
    gen[0] += f[i];
    gen[1] += f[i] * x;
    gen[2] += f[i] * y;
  }
  for (int i = 0; i < 7; ++i) d[i * stride] = at(7 + i);
  for (int r = 0; r < 3; ++r) {
    d[(7 + r) * stride] = c.inv_body_mass[3 * r][q] * gen[0] +
                          c.inv_body_mass[3 * r + 1][q] * gen[1] +
                          c.inv_body_mass[3 * r + 2][q] * gen[2];
  }
  for (int i = 0; i < 4; ++i) {
    d[(10 + i) * stride] = (c.tyre[q] * (road[i] - at(3 + i)) - f[i]) * c.inv_unsprung[i][q];
  }
}

// The transposed layout over all n points. Compiled for x86-64-v3 (AVX2 +
// FMA) and the baseline, chosen at load time; FMA contraction can change the
// last bits relative to derivatives(), never a point's dependence on the batch.
__attribute__((target_clones("arch=x86-64-v3", "default"))) void transposedDerivatives(
    const ConstantPointers& constants, bool tanh_law, double tanh_rate, const double* road,
    const double* __restrict y, double* __restrict d, Eigen::Index n) {
  const ConstantPointers c = constants;  // a local copy: its pointers are loop-invariant
  if (tanh_law) {
#pragma GCC ivdep
    for (Eigen::Index q = 0; q < n; ++q) {
      pointDerivatives<DamperLaw::kTanh>(c, q, tanh_rate, road, y + q, d + q, n);
    }
  } else {
#pragma GCC ivdep
    for (Eigen::Index q = 0; q < n; ++q) {
      pointDerivatives<DamperLaw::kLinear>(c, q, tanh_rate, road, y + q, d + q, n);
    }
  }
}

// Per point, what the general right-hand side (heights, anti-roll bars, a
// horizontal motion: docs/models.md) needs beyond PointConstants.
struct ElevatedPoint {
  Eigen::Matrix3d body_mass;  // M_b with m_s h_b^2 + M h_M^2 on both rotational terms
  double bar[2];              // k_a, front and rear
  double first_moment;        // S = m_s h_b + M h_M
  double static_pitch, static_roll;  // S g tan(theta_s), S g tan(phi_s)
  double pitch_static, roll_static;  // theta_s, phi_s
  double gravity;
  double transfer_x, transfer_y;  // Delta F_x / a_x and Delta F_y / a_y (the links)
};

// One point with heights, bars or a horizontal motion (a_x, a_y):
//   the bars: -k_a (u_l - u_r) on the left end of an axle, +k_a (u_l - u_r)
//     on the right, the opposite on the unsprung masses;
//   M_b q'' = sum f_i [1, x_i, y_i]
//             + [0, S (a_x cos(theta) + (g + z'') sin(theta)) - cos(theta) S g tan(theta_s),
//                   S (a_y cos(phi) + (g + z'') sin(phi)) - cos(phi) S g tan(phi_s)],
//   theta = theta_s + the state's, phi = phi_s + the state's; the z'' terms
//   are taken to the left (M_b's first column gains -S sin(theta), -S sin(phi)),
//   so the equations are solved as they stand;
//   the links' load transfer on the unsprung masses: +Delta F_x / 2 on each
//   front wheel, -Delta F_x / 2 on each rear; +Delta F_y / 2 on each left
//   wheel, -Delta F_y / 2 on each right.
// Not the hot loop of the paper's cases: per point, the library sin and cos.
template <DamperLaw law>
void elevatedPointDerivatives(const ConstantPointers& c, const ElevatedPoint& e, Eigen::Index q,
                              double tanh_rate, const double road[4], double a_x, double a_y,
                              const double* s, double* d, Eigen::Index stride) {
  const auto at = [&](int i) { return s[i * stride]; };
  double f[4], u[4];
  for (int i = 0; i < 4; ++i) {
    const double x = c.x[i][q], y = c.y[i][q];
    u[i] = at(0) + x * at(1) + y * at(2) - at(3 + i);
    const double v = at(7) + x * at(8) + y * at(9) - at(10 + i);
    f[i] = -springIncrement(u[i], c.k[i][q], c.k3[i][q], c.three_delta[i][q],
                            c.three_delta_sq[i][q]) -
           damperForce<law>(c.damping[i][q], tanh_rate, v);
  }
  for (int axle = 0; axle < 2; ++axle) {
    const int left = 2 * axle, right = left + 1;
    const double twist = e.bar[axle] * (u[left] - u[right]);
    f[left] -= twist;
    f[right] += twist;
  }
  Eigen::Vector3d gen(0.0, 0.0, 0.0);
  for (int i = 0; i < 4; ++i) gen += f[i] * Eigen::Vector3d(1.0, c.x[i][q], c.y[i][q]);
  const double theta = e.pitch_static + at(1), phi = e.roll_static + at(2);
  const double cos_theta = std::cos(theta), sin_theta = std::sin(theta);
  const double cos_phi = std::cos(phi), sin_phi = std::sin(phi);
  const double S = e.first_moment;
  gen[1] += S * (a_x * cos_theta + e.gravity * sin_theta) - cos_theta * e.static_pitch;
  gen[2] += S * (a_y * cos_phi + e.gravity * sin_phi) - cos_phi * e.static_roll;
  Eigen::Matrix3d mass = e.body_mass;
  mass(1, 0) -= S * sin_theta;
  mass(2, 0) -= S * sin_phi;
  const Eigen::Vector3d acc = mass.inverse() * gen;
  for (int i = 0; i < 7; ++i) d[i * stride] = at(7 + i);
  for (int r = 0; r < 3; ++r) d[(7 + r) * stride] = acc[r];
  const double dfx = e.transfer_x * a_x, dfy = e.transfer_y * a_y;
  for (int i = 0; i < 4; ++i) {
    const double link = 0.5 * ((i < 2 ? dfx : -dfx) + (i % 2 == 0 ? dfy : -dfy));
    d[(10 + i) * stride] =
        (c.tyre[q] * (road[i] - at(3 + i)) - f[i] + link) * c.inv_unsprung[i][q];
  }
}

class FullCarBatch : public ModelBatch {
 public:
  FullCarBatch(PointConstants c, DamperLaw law, double tanh_rate,
               std::shared_ptr<const ContactRoad> road,
               std::unique_ptr<FullCarReadings> readings = nullptr,
               std::vector<ElevatedPoint> elevated = {})
      : c_(std::move(c)),
        p_(c_),
        law_(law),
        tanh_rate_(tanh_rate),
        road_(std::move(road)),
        motion_(road_->horizontalMotion()),
        elevated_(std::move(elevated)),
        r_(std::move(readings)) {}
  FullCarBatch(const FullCarBatch&) = delete;
  FullCarBatch& operator=(const FullCarBatch&) = delete;

  int pointCount() const override { return static_cast<int>(c_.size()); }

  Eigen::ArrayXXd initialState() const override {
    Eigen::ArrayXXd y =
        Eigen::ArrayXXd::Zero(r_ ? 14 + FullCarModel::kChannels : 14, pointCount());  // the equilibrium
    if (r_) readings(0.0, y);
    return y;
  }

  // Rows 14..28: u_fl .. u_rr, v_fl .. v_rr, accel_y, accel_z, gyro_x, gyro_y,
  // accel_x, speed, gyro_z (the motion's, the same at every point).
  void readings(double t, Eigen::ArrayXXd& y) const override {
    if (!r_) return;
    thread_local Eigen::ArrayXXd dynamic, rates;
    dynamic = y.topRows(14);
    derivatives(t, dynamic, rates);
    const FullCarReadings& r = *r_;
    const HorizontalState drive = motion_ ? motion_->at(t) : HorizontalState();
    y.row(27).setConstant(drive.speed);
    y.row(28).setConstant(drive.yaw_rate);
    for (Eigen::Index q = 0; q < pointCount(); ++q) {
      for (int i = 0; i < 4; ++i) {
        const double x = r.corner_x(i, q), yc = r.corner_y(i, q);
        y(14 + i, q) = y(0, q) + x * y(1, q) + yc * y(2, q) - y(3 + i, q) - r.travel_offset(i, q);
        y(18 + i, q) = y(7, q) + x * y(8, q) + yc * y(9, q) - y(10 + i, q);
      }
      const double a = rates(7, q) + r.imu_x[q] * rates(8, q) + r.imu_y[q] * rates(9, q);
      const double roll = r.roll_static[q] + y(2, q);
      const double pitch = r.pitch_static[q] - y(1, q);  // REP 103: -theta
      const double specific = (r.gravity[q] + a) * std::cos(pitch);
      y(24, q) = y(9, q);
      y(25, q) = -y(8, q);
      // docs/models.md: a_x, the (g + z'') theta tilt, and the IMU's height
      // and lever (x_I) in the pitch's accelerations.
      const double z = r.imu_height[q], theta = -pitch;
      y(26, q) = drive.longitudinal + (r.gravity[q] + rates(7, q)) * theta - z * rates(8, q) -
                 r.imu_x[q] * y(8, q) * y(8, q) - r.rest_x[q];
      if (r.elevated) {
        y(22, q) = specific * std::sin(roll) + drive.lateral * std::cos(roll) - z * rates(9, q) -
                   r.rest_y[q];
        y(23, q) = specific * std::cos(roll) - drive.lateral * roll -
                   drive.longitudinal * theta - z * (y(9, q) * y(9, q) + y(8, q) * y(8, q)) -
                   r.rest_z[q];
        continue;
      }
      y(22, q) = specific * std::sin(roll) - r.rest_y[q];
      y(23, q) = specific * std::cos(roll) - r.rest_z[q];
    }
  }

  void derivatives(double t, const Eigen::ArrayXXd& y, Eigen::ArrayXXd& dydt) const override {
    if (y.rows() != 14 || y.cols() != pointCount()) {
      throw std::invalid_argument("FullCarModel: state batch must be 14 x pointCount()");
    }
    dydt.resize(14, y.cols());
    Eigen::Vector4d road;
    road_->heights(t, road);
    if (!elevated_.empty()) {
      elevatedDerivatives(t, road, &y(0, 0), y.rows(), 1, &dydt(0, 0), dydt.rows());
      return;
    }
    for (Eigen::Index q = 0; q < y.cols(); ++q) {
      if (law_ == DamperLaw::kTanh) {
        pointDerivatives<DamperLaw::kTanh>(p_, q, tanh_rate_, road.data(), &y(0, q), &dydt(0, q),
                                           1);
      } else {
        pointDerivatives<DamperLaw::kLinear>(p_, q, tanh_rate_, road.data(), &y(0, q), &dydt(0, q),
                                             1);
      }
    }
  }

  bool hasTransposedDerivatives() const override { return true; }

  void derivativesTransposed(double t, const Eigen::ArrayXXd& y,
                             Eigen::ArrayXXd& dydt) const override {
    const Eigen::Index n = pointCount();
    if (y.cols() != 14 || y.rows() != n) {
      throw std::invalid_argument("FullCarModel: transposed batch must be pointCount() x 14");
    }
    dydt.resize(n, 14);
    Eigen::Vector4d road;
    road_->heights(t, road);
    if (!elevated_.empty()) {
      elevatedDerivatives(t, road, y.data(), 1, n, dydt.data(), 1);
      return;
    }
    transposedDerivatives(p_, law_ == DamperLaw::kTanh, tanh_rate_, road.data(), y.data(),
                          dydt.data(), n);
  }

 private:
  // Every point by elevatedPointDerivatives: point q's state variable s at
  // y[q * step + s * stride] (either layout; d likewise with d_step).
  void elevatedDerivatives(double t, const Eigen::Vector4d& road, const double* y,
                           Eigen::Index step, Eigen::Index stride, double* d,
                           Eigen::Index d_step) const {
    const HorizontalState drive = motion_ ? motion_->at(t) : HorizontalState();
    for (Eigen::Index q = 0; q < pointCount(); ++q) {
      const ElevatedPoint& e = elevated_[static_cast<std::size_t>(q)];
      if (law_ == DamperLaw::kTanh) {
        elevatedPointDerivatives<DamperLaw::kTanh>(p_, e, q, tanh_rate_, road.data(),
                                                   drive.longitudinal, drive.lateral,
                                                   y + q * step, d + q * d_step, stride);
      } else {
        elevatedPointDerivatives<DamperLaw::kLinear>(p_, e, q, tanh_rate_, road.data(),
                                                     drive.longitudinal, drive.lateral,
                                                     y + q * step, d + q * d_step, stride);
      }
    }
  }

  PointConstants c_;
  ConstantPointers p_;
  DamperLaw law_;
  double tanh_rate_;
  std::shared_ptr<const ContactRoad> road_;
  const HorizontalMotion* motion_;  // owned by road_; null: a_x = a_y = 0
  std::vector<ElevatedPoint> elevated_;  // empty: today's right-hand side for every point
  std::unique_ptr<FullCarReadings> r_;  // null: readings not kept as states
};

void setConstants(const FullCarColumn& p, const FullCarEquilibrium& e, double damper_scale,
                  Eigen::Index q, PointConstants& c) {
  using C = PointConstants;
  const FullCarFields<int>& at = p.at();
  for (int i = 0; i < 4; ++i) {
    const int axle = FullCarParameters::axle(i);
    const double delta = e.spring_compression[i];
    c(q, C::kX + i) = p.cornerX(i);
    c(q, C::kY + i) = p.cornerY(i);
    c(q, C::kK + i) = p[at.spring_linear[axle]];
    c(q, C::kK3 + i) = p[at.spring_cubic[axle]];
    c(q, C::kThreeDelta + i) = 3.0 * delta;
    c(q, C::kThreeDeltaSq + i) = 3.0 * delta * delta;
    c(q, C::kDamping + i) = p[at.damping[axle]] * damper_scale;
    c(q, C::kInvUnsprung + i) = 1.0 / p[at.unsprung_mass[axle]];
  }
  c(q, C::kTyre) = p[at.tyre_stiffness];
  const Eigen::Matrix3d inv = p.bodyMass().inverse();
  for (int r = 0; r < 3; ++r) {
    for (int col = 0; col < 3; ++col) c(q, C::kInvBodyMass + 3 * r + col) = inv(r, col);
  }
}

// The general right-hand side's constants of one point; whether the point has
// heights or bars (the general right-hand side is then needed).
bool elevatedConstants(const FullCarColumn& p, const FullCarEquilibrium& e, ElevatedPoint& out) {
  const FullCarFields<int>& at = p.at();
  const double g = p[at.gravity], m = p[at.added_mass], body = p[at.body_mass];
  out.body_mass = p.bodyMass();
  out.bar[0] = p[at.anti_roll_bar[0]];
  out.bar[1] = p[at.anti_roll_bar[1]];
  out.first_moment = body * p[at.body_cg_height] + m * p[at.added_mass_height];
  // tan(theta_s), tan(phi_s): the equilibrium's corner-plane slopes, and the
  // angles theta_s = atan(slope), phi_s likewise (so that at rest the S g sin
  // terms cancel the S g tan ones exactly).
  out.static_pitch = out.first_moment * g * e.pitch;
  out.static_roll = out.first_moment * g * e.roll;
  out.pitch_static = std::atan(e.pitch);
  out.roll_static = std::atan(e.roll);
  out.gravity = g;
  const double unsprung = 2.0 * (p[at.unsprung_mass[0]] + p[at.unsprung_mass[1]]);
  const double lever = (body + m) * p[at.mount_height] + unsprung * p[at.wheel_radius];
  out.transfer_x = lever / (p[at.front_axle_distance] + p[at.rear_axle_distance]);
  out.transfer_y = lever / p[at.track_width];
  return p[at.body_cg_height] != 0.0 || p[at.added_mass_height] != 0.0 || out.bar[0] != 0.0 ||
         out.bar[1] != 0.0;
}

}  // namespace

Eigen::Matrix3d FullCarColumn::bodyMass() const {
  const double m = v_[at_.added_mass], xm = addedMassX(), ym = addedMassY();
  const double body = v_[at_.body_mass];
  double pitch = v_[at_.pitch_inertia], roll = v_[at_.roll_inertia];
  const double h_b = v_[at_.body_cg_height], h_m = v_[at_.added_mass_height];
  if (h_b != 0.0 || h_m != 0.0) {
    // The elevated masses about the mount plane's axes (docs/models.md).
    const double elevated = body * h_b * h_b + m * h_m * h_m;
    pitch += elevated;
    roll += elevated;
  }
  Eigen::Matrix3d mb;
  // clang-format off
  mb << body + m, m * xm,              m * ym,
        m * xm,   pitch + m * xm * xm, m * xm * ym,
        m * ym,   m * xm * ym,         roll + m * ym * ym;
  // clang-format on
  return mb;
}

FullCarModel::FullCarModel(ModelParameters nominal, std::shared_ptr<const ContactRoad> road,
                           ReadingSettings readings)
    : nominal_(FullCarParameters::from(nominal)),
      readings_(readings),
      state_names_(fullCarDescription().stateNames()),
      nominal_vector_(std::move(nominal.values)),
      h_(Eigen::MatrixXd::Zero(kChannels, 14)),
      road_(std::move(road)) {
  // Tare offsets depend on each point's parameters: readings as states.
  if (readings_.zero == ZeroConvention::kTare) readings_.as_states = true;
  checkModelOnRoad(*this, road_.get(), "FullCarModel");
  checkDamperSettings("FullCarModel", nominal_.damper, nominal_.damper_tanh_scale,
                      nominal_.damper_tanh_rate);
  if (readings_.as_states) {
    for (const std::string& c : fullCarDescription().channelNames()) {
      state_names_.push_back("reading_" + c);
    }
    h_ = Eigen::MatrixXd::Zero(kChannels, 14 + kChannels);
    h_.rightCols(kChannels).setIdentity();
    return;
  }
  // u_i = z + x_i theta + y_i phi - zu_i and its rate, with the nominal
  // geometry; the IMU rows stay zero (channelModelled is false for them).
  for (int i = 0; i < 4; ++i) {
    const double x = nominal_.cornerX(i), y = nominal_.cornerY(i);
    for (int rate = 0; rate < 2; ++rate) {
      const int row = 4 * rate + i, col = 7 * rate;
      h_(row, col) = 1.0;
      h_(row, col + 1) = x;
      h_(row, col + 2) = y;
      h_(row, col + 3 + i) = -1.0;
    }
  }
}

std::string FullCarModel::invalidReason(const Eigen::Ref<const Eigen::VectorXd>& params) const {
  // The table's branch-free test first (every point of every forecast); the
  // message only for a point that fails it.
  const ParameterTable& table = description().parameters();
  if (params.size() != table.size() || !table.admissible(params.data())) {
    const std::string why = table.violation(params);
    if (!why.empty()) return why;
  }
  try {
    equilibrium(params);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

FullCarEquilibrium FullCarModel::equilibrium(const Eigen::Ref<const Eigen::VectorXd>& params) const {
  // On the heap, made at the thread's first solve: a thread_local table of
  // this size would sit in the library's static TLS, which every thread of
  // the process (PDF workers, the writer, ...) zeroes when it starts.
  thread_local std::unique_ptr<EquilibriumMemo> memo;
  if (!memo) memo = std::make_unique<EquilibriumMemo>();
  const FullCarEquilibriumKey key = fullCarEquilibriumKey(FullCarColumn(params.data()));
  EquilibriumMemo::Slot& slot = memo->slots[EquilibriumMemo::slotOf(key)];
  if (!slot.used || std::memcmp(slot.key.data(), key.data(), sizeof(double) * key.size()) != 0) {
    std::optional<FullCarEquilibrium> start;
    if (const EquilibriumMemo::Slot* n = memo->near(key)) start = n->equilibrium;
    slot.used = true;
    slot.key = key;
    slot.error.clear();
    try {
      const FullCarColumn column(params.data());
      slot.equilibrium = start ? solveFullCarEquilibriumFrom(column, *start)
                               : solveFullCarEquilibrium(column);
    } catch (const std::runtime_error& e) {
      slot.error = e.what();
    }
    memo->solved(&slot);
  }
  if (!slot.error.empty()) throw std::runtime_error(slot.error);
  return slot.equilibrium;
}

std::unique_ptr<ModelBatch> FullCarModel::prepare(const Eigen::MatrixXd& params) const {
  if (params.rows() != nominal_vector_.size()) {
    throw std::invalid_argument("FullCarModel::prepare: expected " +
                                std::to_string(nominal_vector_.size()) + " parameter rows");
  }
  const double scale = nominal_.damper == DamperLaw::kTanh ? nominal_.damper_tanh_scale : 1.0;
  PointConstants points(params.cols());
  const HorizontalMotion* motion = road_->horizontalMotion();
  bool elevated = motion && motion->accelerates();
  std::vector<ElevatedPoint> general(static_cast<std::size_t>(params.cols()));
  for (Eigen::Index q = 0; q < params.cols(); ++q) {
    const std::string prefix = "FullCarModel::prepare: column " + std::to_string(q) + ": ";
    const std::string why = description().parameters().violation(params.col(q));
    if (!why.empty()) throw std::invalid_argument(prefix + why);
    const FullCarColumn p(&params(0, q));
    FullCarEquilibrium e;
    try {
      e = equilibrium(params.col(q));
    } catch (const std::runtime_error& error) {
      throw std::invalid_argument(prefix + error.what());
    }
    setConstants(p, e, scale, q, points);
    elevated = elevatedConstants(p, e, general[static_cast<std::size_t>(q)]) || elevated;
  }
  if (!elevated) general.clear();
  std::unique_ptr<FullCarReadings> r;
  if (readings_.as_states) {
    r = readingConstants(params);
    r->elevated = elevated || (r->imu_height != 0.0).any();
  }
  return std::make_unique<FullCarBatch>(std::move(points), nominal_.damper,
                                        nominal_.damper_tanh_rate, road_, std::move(r),
                                        std::move(general));
}

std::unique_ptr<FullCarReadings> FullCarModel::readingConstants(const Eigen::MatrixXd& params) const {
  const Eigen::Index count = params.cols();
  auto r = std::make_unique<FullCarReadings>();
  r->corner_x.resize(4, count);
  r->corner_y.resize(4, count);
  r->travel_offset = Eigen::ArrayXXd::Zero(4, count);
  for (Eigen::ArrayXd* a : {&r->imu_x, &r->imu_y, &r->gravity, &r->roll_static, &r->pitch_static,
                            &r->rest_y, &r->rest_z, &r->rest_x, &r->imu_height}) {
    a->resize(count);
  }
  const bool tare = readings_.zero == ZeroConvention::kTare;
  const FullCarFields<int>& at = fullCarRows();
  for (Eigen::Index q = 0; q < count; ++q) {
    const FullCarColumn p(&params(0, q));
    const FullCarEquilibrium e = equilibrium(params.col(q));
    for (int i = 0; i < 4; ++i) {
      r->corner_x(i, q) = p.cornerX(i);
      r->corner_y(i, q) = p.cornerY(i);
    }
    r->imu_x[q] = p[at.imu_x];
    r->imu_y[q] = p[at.imu_y];
    r->gravity[q] = p[at.gravity];
    r->roll_static[q] = e.roll;
    r->pitch_static[q] = -e.pitch;
    const double level = p[at.gravity] * std::cos(-e.pitch);
    r->rest_y[q] = tare ? 0.0 : level * std::sin(e.roll);
    r->rest_z[q] = tare ? 0.0 : level * std::cos(e.roll);
    r->rest_x[q] = tare ? 0.0 : p[at.gravity] * e.pitch;
    r->imu_height[q] = p[at.imu_height];
    if (!tare) continue;
    // Zeroed on the empty vehicle: the same vehicle without the load.
    Eigen::VectorXd unloaded = params.col(q);
    unloaded[at.added_mass] = 0.0;
    const FullCarEquilibrium empty = equilibrium(unloaded);
    for (int i = 0; i < 4; ++i) {
      r->travel_offset(i, q) = e.spring_compression[i] - empty.spring_compression[i];
    }
  }
  return r;
}

std::vector<double> FullCarModel::breakpoints(double t0, double t1) const {
  return road_->breakpoints(t0, t1);
}

}  // namespace pc_ekf
