// Roll-plane vehicle model (docs/method.md §1): parameter checks and batched right-hand side.
#include "pc_ekf/model/roll_plane_model.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "pc_ekf/model/domain_message.h"
#include "pc_ekf/model/horizontal_motion.h"
#include "pc_ekf/model/smooth_functions.h"

namespace pc_ekf {

// What each point's readings need beyond its dynamics (readings as states).
struct RollPlaneReadings {
  Eigen::ArrayXd imu_fraction;      // s / L: a = (1 - s/L) x1dd + (s/L) x2dd
  Eigen::ArrayXd inv_length;
  Eigen::ArrayXd gravity;
  Eigen::ArrayXd roll_static;       // phi_s = -theta_s (REP 103)
  Eigen::ArrayXd rest_y, rest_z;    // subtracted: g sin(phi_s), g cos(phi_s) (rest); 0 (tare)
  Eigen::ArrayXXd travel_offset;    // 2 x Q, subtracted from u_i: 0 (rest); sag (tare)
  // Heights or a horizontal motion (docs/models.md): the IMU's height z_I, and
  // whether the channels take the lateral acceleration and z_I terms.
  Eigen::ArrayXd imu_height;
  bool elevated = false;
};

namespace {

// Raw views of the per-point constants for the vectorised loop, one array per
// quantity (structure of arrays over the Q points), so the right-hand side
// does no equilibrium or parameter work.
struct ConstantPointers {
  const double *k[2], *k3[2];        // spring law
  const double *three_delta[2];      // 3 delta_i
  const double *three_delta_sq[2];   // 3 delta_i^2
  const double *damping[2];          // c (linear) or c * tanh scale
  const double *tyre[2], *inv_unsprung[2];
  const double *inv_total_mass;                       // 1 / (m + M)
  const double *roll_gain;                            // L / I_cg
  const double *cg, *rear_arm, *cg_ratio;             // D, L - D, D / L
  const double *inv_length;                           // 1 / L
  const double *roll_static, *cos_static, *sin_static;  // theta_s, cos and sin of it
  // Heights, anti-roll bar, lateral acceleration (docs/models.md).
  const double *bar;             // k_a
  const double *first_moment;    // S = m h_b + M h_M
  const double *static_moment;   // S g tan(phi_s)
  const double *gravity;
  const double *transfer;        // Delta F_y / a_y = ((m + M) h_P + sum m_t r_w) / L
  const DamperCurve* curve[2] = {nullptr, nullptr};  // the table law's curves
};

// The constants in one Q x kCount table (one allocation per prepare()).
struct PointConstants : PointConstantTable {
  enum Column {
    kK = 0, kK3 = 2, kThreeDelta = 4, kThreeDeltaSq = 6, kDamping = 8, kTyre = 10,
    kInvUnsprung = 12, kInvTotalMass = 14, kRollGain, kCg, kRearArm, kCgRatio, kInvLength,
    kRollStatic, kCosStatic, kSinStatic, kBar, kFirstMoment, kStaticMoment, kGravity, kTransfer,
    kCount
  };
  explicit PointConstants(Eigen::Index q) : PointConstantTable(q, kCount) {}
  ConstantPointers pointers() const {
    const auto col = [this](int c) { return column(c); };
    ConstantPointers p;
    for (int i = 0; i < 2; ++i) {
      p.k[i] = col(kK + i);
      p.k3[i] = col(kK3 + i);
      p.three_delta[i] = col(kThreeDelta + i);
      p.three_delta_sq[i] = col(kThreeDeltaSq + i);
      p.damping[i] = col(kDamping + i);
      p.tyre[i] = col(kTyre + i);
      p.inv_unsprung[i] = col(kInvUnsprung + i);
    }
    p.inv_total_mass = col(kInvTotalMass);
    p.roll_gain = col(kRollGain);
    p.cg = col(kCg);
    p.rear_arm = col(kRearArm);
    p.cg_ratio = col(kCgRatio);
    p.inv_length = col(kInvLength);
    p.roll_static = col(kRollStatic);
    p.cos_static = col(kCosStatic);
    p.sin_static = col(kSinStatic);
    p.bar = col(kBar);
    p.first_moment = col(kFirstMoment);
    p.static_moment = col(kStaticMoment);
    p.gravity = col(kGravity);
    p.transfer = col(kTransfer);
    return p;
  }
};

// The damper force of suspension i at point q: c * scale * tanh(rate v),
// c v, or c / c_ref * curve(v) (the damping column holds c / c_ref).
template <DamperLaw law>
inline double damperAt(const ConstantPointers& c, int i, Eigen::Index q, double tanh_rate,
                       double v) {
  if (law == DamperLaw::kTable) return c.damping[i][q] * (*c.curve[i])(v);
  return damperForce<law>(c.damping[i][q], tanh_rate, v);
}

// Paper eq. 40-41 solved for the body-end accelerations, and eq. 42-43. `lever`
// is cos(theta_s + theta). Shared by the per-point and the vectorised loops so
// both give the same bits.
struct Accelerations {
  double body[2], wheel[2];
};
inline Accelerations accelerations(const ConstantPointers& c, Eigen::Index q, const double f[2],
                                   double lever, double road0, double road1, double xr1,
                                   double xr2) {
  const double a_cg = (f[0] + f[1]) * c.inv_total_mass[q];
  const double rel = lever * c.roll_gain[q] * (c.rear_arm[q] * f[1] - c.cg[q] * f[0]);  // x2dd - x1dd
  const double a1 = a_cg - rel * c.cg_ratio[q];
  Accelerations a;
  a.body[0] = a1;
  a.body[1] = a1 + rel;
  a.wheel[0] = (c.tyre[0][q] * (road0 - xr1) - f[0]) * c.inv_unsprung[0][q];
  a.wheel[1] = (c.tyre[1][q] * (road1 - xr2) - f[1]) * c.inv_unsprung[1][q];
  return a;
}

// One point's spring and damper forces on the body ends, f[i] = -(spring
// increment + damper force) of side i; shared by pointDerivatives and
// elevatedPointDerivatives (any stride).
template <DamperLaw law>
inline void suspensionForces(const ConstantPointers& c, Eigen::Index q, double tanh_rate,
                             const double* s, Eigen::Index s_stride, double f[2]) {
  for (int i = 0; i < 2; ++i) {
    const double u = s[i * s_stride] - s[(2 + i) * s_stride];
    const double v = s[(4 + i) * s_stride] - s[(6 + i) * s_stride];
    f[i] = -springIncrement(u, c.k[i][q], c.k3[i][q], c.three_delta[i][q], c.three_delta_sq[i][q]) -
           damperAt<law>(c, i, q, tanh_rate, v);
  }
}

// One point, state s[8] -> d[8] (any strides); cos by cosOfSum (library beyond the series).
template <DamperLaw law>
inline void pointDerivatives(const ConstantPointers& c, Eigen::Index q, double tanh_rate,
                             double road0, double road1, const double* s, Eigen::Index s_stride,
                             double* d, Eigen::Index d_stride) {
  double f[2];
  suspensionForces<law>(c, q, tanh_rate, s, s_stride, f);
  const double theta = (s[s_stride] - s[0]) * c.inv_length[q];
  const double lever = cosOfSum(c.roll_static[q], c.cos_static[q], c.sin_static[q], theta);
  const Accelerations a =
      accelerations(c, q, f, lever, road0, road1, s[2 * s_stride], s[3 * s_stride]);
  for (int i = 0; i < 4; ++i) d[i * d_stride] = s[(4 + i) * s_stride];
  d[4 * d_stride] = a.body[0];
  d[5 * d_stride] = a.body[1];
  d[6 * d_stride] = a.wheel[0];
  d[7 * d_stride] = a.wheel[1];
}

// One point with heights, an anti-roll bar or a lateral acceleration a_y
// (docs/models.md): the bar's forces -k_a (u1 - u2) on the left end and
// +k_a (u1 - u2) on the right (the opposite on the unsprung masses),
//   (m + M) a_P = f_1 + f_2,
//   J phi'' = cos(phi) (D f_1 - (L - D) f_2 - S g tan(phi_s)) + S (a_y cos(phi) + (g + a_P) sin(phi)),
// phi = -(theta_s + theta) (REP 103), and the links' load transfer +-Delta F_y
// on the unsprung masses. The library cos and sin: this path is not the hot
// loop of the paper's cases. Returns phi''.
template <DamperLaw law>
inline double elevatedPointDerivatives(const ConstantPointers& c, Eigen::Index q,
                                       double tanh_rate, double road0, double road1,
                                       double lateral, const double* s, Eigen::Index s_stride,
                                       double* d, Eigen::Index d_stride) {
  double f[2];
  suspensionForces<law>(c, q, tanh_rate, s, s_stride, f);
  const double twist = c.bar[q] * ((s[0] - s[2 * s_stride]) - (s[s_stride] - s[3 * s_stride]));
  f[0] -= twist;
  f[1] += twist;
  const double angle = c.roll_static[q] + (s[s_stride] - s[0]) * c.inv_length[q];  // -phi
  const double cos_phi = std::cos(angle), sin_phi = -std::sin(angle);
  const double a_p = (f[0] + f[1]) * c.inv_total_mass[q];
  const double moment =
      cos_phi * (c.cg[q] * f[0] - c.rear_arm[q] * f[1] - c.static_moment[q]) +
      c.first_moment[q] * (lateral * cos_phi + (c.gravity[q] + a_p) * sin_phi);
  // roll_gain = L / J; x2'' - x1'' = -L phi''.
  const double rel = -c.roll_gain[q] * moment;
  const double a1 = a_p - rel * c.cg_ratio[q];
  const double transfer = c.transfer[q] * lateral;
  for (int i = 0; i < 4; ++i) d[i * d_stride] = s[(4 + i) * s_stride];
  d[4 * d_stride] = a1;
  d[5 * d_stride] = a1 + rel;
  d[6 * d_stride] =
      (c.tyre[0][q] * (road0 - s[2 * s_stride]) - f[0] + transfer) * c.inv_unsprung[0][q];
  d[7 * d_stride] =
      (c.tyre[1][q] * (road1 - s[3 * s_stride]) - f[1] - transfer) * c.inv_unsprung[1][q];
  return -rel * c.inv_length[q];
}

// All points, structure of arrays: y and d hold state variable s of point q at
// [s * n + q]. Three passes, each short enough to vectorise without register
// spills: (1) velocities -> d[0..3], damper arguments -> d[4..5] (scratch);
// (2) tanh in place over those 2n values; (3) forces and accelerations ->
// d[4..7]. Branch-free (the cos series for every point); returns whether any
// point has |theta| > 0.25 rad, which the caller then redoes with
// pointDerivatives.
template <DamperLaw law>
__attribute__((always_inline)) inline bool soaDerivatives(const ConstantPointers& constants,
                                                         double tanh_rate, double road0,
                                                         double road1, const double* __restrict y,
                                                         double* __restrict d, Eigen::Index n) {
  const ConstantPointers c = constants;  // a local copy: its pointers are loop-invariant
  // Outputs never alias inputs or constants (separate arrays).
#pragma GCC ivdep
  for (Eigen::Index q = 0; q < n; ++q) {
    for (int i = 0; i < 4; ++i) d[i * n + q] = y[(4 + i) * n + q];
    for (int i = 0; i < 2; ++i) {
      const double v = y[(4 + i) * n + q] - y[(6 + i) * n + q];
      d[(4 + i) * n + q] = law == DamperLaw::kTanh ? tanh_rate * v : v;
    }
  }
  if (law == DamperLaw::kTanh) {
    double* __restrict t = d + 4 * n;
    // Slow suspension motion (every |argument| < 0.625, e.g. after the bump):
    // the rational branch alone; fast motion: the exponential form alone (the
    // same values as fastTanh either way).
    long near_zero = 0;
    for (Eigen::Index j = 0; j < 2 * n; ++j) near_zero += std::abs(t[j]) < 0.625;
    if (near_zero == 2 * n) {
      for (Eigen::Index j = 0; j < 2 * n; ++j) t[j] = fastTanhNearZero(t[j]);
    } else if (near_zero == 0) {  // fast motion (the bump): the exponential form alone
      for (Eigen::Index j = 0; j < 2 * n; ++j) t[j] = fastTanhFarFromZero(t[j]);
    } else {
      for (Eigen::Index j = 0; j < 2 * n; ++j) t[j] = fastTanh(t[j]);
    }
  }
  if (law == DamperLaw::kTable) {  // the curves in place; c * curve below
    double* __restrict t = d + 4 * n;
    for (int i = 0; i < 2; ++i) {
      const DamperCurve& curve = *c.curve[i];
      for (Eigen::Index q = 0; q < n; ++q) t[i * n + q] = curve(t[i * n + q]);
    }
  }
  long beyond_series = 0;
#pragma GCC ivdep
  for (Eigen::Index q = 0; q < n; ++q) {
    double f[2];
    for (int i = 0; i < 2; ++i) {
      const double u = y[i * n + q] - y[(2 + i) * n + q];
      f[i] = -springIncrement(u, c.k[i][q], c.k3[i][q], c.three_delta[i][q],
                              c.three_delta_sq[i][q]) -
             c.damping[i][q] * d[(4 + i) * n + q];
    }
    const double theta = (y[n + q] - y[q]) * c.inv_length[q];
    beyond_series |= !cosOfSumSeriesValid(theta);
    const double lever = cosOfSumSeries(c.cos_static[q], c.sin_static[q], theta);
    const Accelerations a = accelerations(c, q, f, lever, road0, road1, y[2 * n + q], y[3 * n + q]);
    d[4 * n + q] = a.body[0];
    d[5 * n + q] = a.body[1];
    d[6 * n + q] = a.wheel[0];
    d[7 * n + q] = a.wheel[1];
  }
  return beyond_series != 0;
}

// The hot loop of every forecast. Compiled for x86-64-v3 (AVX2 + FMA: 4 points
// per instruction) and for the baseline, chosen at load time. Within a build
// every point's value is independent of the batch it is in (the vector body
// and the remainder loop contract the same expressions).
__attribute__((target_clones("arch=x86-64-v3", "default"))) bool soaDerivativesDispatch(
    const ConstantPointers& c, DamperLaw law, double tanh_rate, double road0, double road1,
    const double* __restrict y, double* __restrict d, Eigen::Index n) {
  switch (law) {
    case DamperLaw::kTanh:
      return soaDerivatives<DamperLaw::kTanh>(c, tanh_rate, road0, road1, y, d, n);
    case DamperLaw::kTable:
      return soaDerivatives<DamperLaw::kTable>(c, tanh_rate, road0, road1, y, d, n);
    default:
      return soaDerivatives<DamperLaw::kLinear>(c, tanh_rate, road0, road1, y, d, n);
  }
}

// pointDerivatives for the batch's law.
inline void lawPointDerivatives(DamperLaw law, const ConstantPointers& c, Eigen::Index q,
                                double tanh_rate, double road0, double road1, const double* s,
                                Eigen::Index s_stride, double* d, Eigen::Index d_stride) {
  switch (law) {
    case DamperLaw::kTanh:
      return pointDerivatives<DamperLaw::kTanh>(c, q, tanh_rate, road0, road1, s, s_stride, d,
                                                d_stride);
    case DamperLaw::kTable:
      return pointDerivatives<DamperLaw::kTable>(c, q, tanh_rate, road0, road1, s, s_stride, d,
                                                 d_stride);
    default:
      return pointDerivatives<DamperLaw::kLinear>(c, q, tanh_rate, road0, road1, s, s_stride, d,
                                                  d_stride);
  }
}

class RollPlaneBatch : public ModelBatch {
 public:
  // elevated: heights, a bar or a horizontal motion at some point (the
  // general right-hand side for every point).
  RollPlaneBatch(PointConstants c, DamperLaw law, double tanh_rate, const DamperCurve curves[2],
                 std::shared_ptr<const ContactRoad> road, bool elevated,
                 std::unique_ptr<RollPlaneReadings> readings = nullptr)
      : c_(std::move(c)),
        p_(c_.pointers()),
        law_(law),
        tanh_rate_(tanh_rate),
        curves_{curves[0], curves[1]},
        road_(std::move(road)),
        motion_(road_->horizontalMotion()),
        elevated_(elevated),
        r_(std::move(readings)) {
    p_.curve[0] = &curves_[0];
    p_.curve[1] = &curves_[1];
  }
  RollPlaneBatch(const RollPlaneBatch&) = delete;
  RollPlaneBatch& operator=(const RollPlaneBatch&) = delete;

  int pointCount() const override { return static_cast<int>(c_.size()); }

  Eigen::ArrayXXd initialState() const override {
    // The equilibrium (docs/method.md §1.4), and its readings.
    Eigen::ArrayXXd y = Eigen::ArrayXXd::Zero(r_ ? 8 + RollPlaneModel::kChannels : 8, pointCount());
    if (r_) readings(0.0, y);
    return y;
  }

  // Rows 8..16: u1 u2 v1 v2 accel_y accel_z gyro_x (docs/method.md §1.6), speed
  // gyro_z (the motion's, the same at every point).
  void readings(double t, Eigen::ArrayXXd& y) const override {
    if (!r_) return;
    const Eigen::Index n = pointCount();
    thread_local Eigen::ArrayXXd dynamic, rates;
    dynamic = y.topRows(8);
    derivatives(t, dynamic, rates);
    const RollPlaneReadings& r = *r_;
    const HorizontalState drive = motion_ ? motion_->at(t) : HorizontalState();
    y.row(15).setConstant(drive.speed);
    y.row(16).setConstant(drive.yaw_rate);
    for (Eigen::Index q = 0; q < n; ++q) {
      for (int i = 0; i < 2; ++i) {
        y(8 + i, q) = y(i, q) - y(2 + i, q) - r.travel_offset(i, q);
        y(10 + i, q) = y(4 + i, q) - y(6 + i, q);
      }
      // Vertical acceleration of the IMU point, and the roll (left up > 0).
      const double a = (1.0 - r.imu_fraction[q]) * rates(4, q) + r.imu_fraction[q] * rates(5, q);
      const double phi = r.roll_static[q] - (y(1, q) - y(0, q)) * r.inv_length[q];
      const double specific = r.gravity[q] + a;
      y(14, q) = -(y(5, q) - y(4, q)) * r.inv_length[q];
      if (r.elevated) {
        // docs/models.md: the lateral acceleration and the IMU's height z_I.
        const double lateral = this->lateral(t);
        const double roll_acc = -(rates(5, q) - rates(4, q)) * r.inv_length[q];
        const double z = r.imu_height[q];
        y(12, q) = lateral * std::cos(phi) + specific * std::sin(phi) - z * roll_acc - r.rest_y[q];
        y(13, q) = specific * std::cos(phi) - lateral * phi - z * y(14, q) * y(14, q) - r.rest_z[q];
        continue;
      }
      y(12, q) = specific * std::sin(phi) - r.rest_y[q];
      y(13, q) = specific * std::cos(phi) - r.rest_z[q];
    }
  }

  void derivatives(double t, const Eigen::ArrayXXd& y, Eigen::ArrayXXd& dydt) const override {
    if (y.rows() != 8 || y.cols() != pointCount()) {
      throw std::invalid_argument("RollPlaneModel: state batch must be 8 x pointCount()");
    }
    dydt.resize(8, y.cols());  // no-op when already sized
    Eigen::Vector2d road;
    road_->heights(t, road);
    if (elevated_) {
      elevatedDerivatives(t, road, &y(0, 0), 1, y.rows(), &dydt(0, 0), 1, dydt.rows());
      return;
    }
    for (Eigen::Index q = 0; q < y.cols(); ++q) {
      lawPointDerivatives(law_, p_, q, tanh_rate_, road[0], road[1], &y(0, q), 1, &dydt(0, q), 1);
    }
  }

  bool hasTransposedDerivatives() const override { return true; }

  void derivativesTransposed(double t, const Eigen::ArrayXXd& y,
                             Eigen::ArrayXXd& dydt) const override {
    const Eigen::Index n = pointCount();
    if (y.cols() != 8 || y.rows() != n) {
      throw std::invalid_argument("RollPlaneModel: transposed batch must be pointCount() x 8");
    }
    dydt.resize(n, 8);  // no-op when already sized
    Eigen::Vector2d road;
    road_->heights(t, road);
    if (elevated_) {
      elevatedDerivatives(t, road, y.data(), n, 1, dydt.data(), n, 1);
      return;
    }
    const bool beyond_series = soaDerivativesDispatch(p_, law_, tanh_rate_,
                                                      road[0], road[1], y.data(), dydt.data(), n);
    if (!beyond_series) return;
    // Rolls beyond the series' range (wild parameters, diverging points): redo
    // those points with the library cos.
    for (Eigen::Index q = 0; q < n; ++q) {
      if (cosOfSumSeriesValid((y(q, 1) - y(q, 0)) * p_.inv_length[q])) continue;
      lawPointDerivatives(law_, p_, q, tanh_rate_, road[0], road[1], &y(q, 0), n, &dydt(q, 0), n);
    }
  }

 private:
  double lateral(double t) const { return motion_ ? motion_->at(t).lateral : 0.0; }

  // Every point by elevatedPointDerivatives: point q's state variable s at
  // y[s * stride + q * step] (either layout).
  void elevatedDerivatives(double t, const Eigen::Vector2d& road, const double* y,
                           Eigen::Index stride, Eigen::Index step, double* d,
                           Eigen::Index d_stride, Eigen::Index d_step) const {
    const double a_y = lateral(t);
    for (Eigen::Index q = 0; q < pointCount(); ++q) {
      if (law_ == DamperLaw::kTanh) {
        elevatedPointDerivatives<DamperLaw::kTanh>(p_, q, tanh_rate_, road[0], road[1], a_y,
                                                   y + q * step, stride, d + q * d_step, d_stride);
      } else if (law_ == DamperLaw::kTable) {
        elevatedPointDerivatives<DamperLaw::kTable>(p_, q, tanh_rate_, road[0], road[1], a_y,
                                                    y + q * step, stride, d + q * d_step,
                                                    d_stride);
      } else {
        elevatedPointDerivatives<DamperLaw::kLinear>(p_, q, tanh_rate_, road[0], road[1], a_y,
                                                     y + q * step, stride, d + q * d_step,
                                                     d_stride);
      }
    }
  }

  PointConstants c_;
  ConstantPointers p_;
  DamperLaw law_;
  double tanh_rate_;
  DamperCurve curves_[2];  // law_ == kTable (p_.curve points here)
  std::shared_ptr<const ContactRoad> road_;
  const HorizontalMotion* motion_;  // owned by road_; null: a_y = 0
  bool elevated_;
  std::unique_ptr<RollPlaneReadings> r_;  // null: readings not kept as states
};

// Whether a point has heights or an anti-roll bar in its dynamics.
bool elevatedPoint(const double* p) {
  const RollPlaneFields<int>& at = rollPlaneRows();
  return p[at.body_cg_height] != 0.0 || p[at.added_mass_height] != 0.0 ||
         p[at.anti_roll_bar] != 0.0;
}


}  // namespace

RollPlaneModel::RollPlaneModel(ModelParameters nominal, std::shared_ptr<const ContactRoad> road,
                               ReadingSettings readings)
    : nominal_(std::move(nominal)),
      damper_(damperLaw(nominal_.choice(rollPlaneDescription(), "damper"))),
      tanh_scale_(nominal_.settings[rollPlaneRows().damper_tanh_scale]),
      tanh_rate_(nominal_.settings[rollPlaneRows().damper_tanh_rate]),
      readings_(readings),
      state_names_(rollPlaneDescription().stateNames()),
      h_(Eigen::MatrixXd::Zero(kChannels, 8)),
      road_(std::move(road)) {
  // Tare offsets depend on each point's parameters: readings as states.
  if (readings_.zero == ZeroConvention::kTare) readings_.as_states = true;
  checkModelOnRoad(*this, road_.get(), "RollPlaneModel");
  if (damper_ != DamperLaw::kTable) {
    checkDamperSettings("RollPlaneModel", damper_, tanh_scale_, tanh_rate_);
  }
  rollPlaneDamperCurves(nominal_, curve_);
  if (readings_.as_states) {
    // Each channel's reading is a state row after the dynamic ones.
    for (const std::string& c : rollPlaneDescription().channelNames()) {
      state_names_.push_back("reading_" + c);
    }
    h_ = Eigen::MatrixXd::Zero(kChannels, 8 + kChannels);
    h_.rightCols(kChannels).setIdentity();
    return;
  }
  // u_i = x_i - xr_i, v_i = xidot - xridot (docs/method.md §1.6); the IMU
  // rows stay zero (channelModelled is false for them).
  for (int i = 0; i < 2; ++i) {
    h_(i, i) = 1.0;
    h_(i, 2 + i) = -1.0;
    h_(2 + i, 4 + i) = 1.0;
    h_(2 + i, 6 + i) = -1.0;
  }
}

VehicleParameters RollPlaneModel::nominal() const { return VehicleParameters::from(nominal_); }

// The model's rule across entries, beyond the table's domains: a point's
// added mass may be negative while the total mass and the inertia about the
// combined centre stay positive. Magnitudes below 1e150 keep the inertia
// formula free of overflow (else the detailed check decides).
std::string RollPlaneModel::invalidReason(const Eigen::Ref<const Eigen::VectorXd>& params) const {
  const ParameterTable& table = description().parameters();
  static const RollPlaneFields<int>& at = rollPlaneRows();  // once: it runs for every point
  if (params.size() == table.size() && table.admissible(params.data())) {
    const double largest = params.cwiseAbs().maxCoeff();
    if ((params[at.added_mass] >= 0.0) & (largest < 1e150) &
        (std::abs(params[at.body_cg_offset]) <= 0.5 * params[at.bar_length])) {
      // Heights: the point needs a stable static equilibrium too.
      return rollPlaneEquilibriumRefusal(params);
    }
  }
  const std::string why = table.violation(params);
  if (!why.empty()) return why;
  const auto& names = table.names();
  const double m = params[at.bar_mass], length = params[at.bar_length],
               mass = params[at.added_mass], pos = params[at.added_mass_position];
  const double offset = params[at.body_cg_offset];
  if (!(std::abs(offset) <= 0.5 * length)) {
    return outOfDomain(names[at.body_cg_offset], offset,
                       "puts the body's centre beyond the mounts (bar_length = " +
                           domainNumber(length) + ")");
  }
  if (mass + m <= 0.0) {
    return outOfDomain(names[at.added_mass], mass,
                       "makes the total mass <= 0 (bar_mass = " + domainNumber(m) + ")");
  }
  // A negative added mass can still make the combined inertia non-positive.
  const double body = 0.5 * length - offset;  // the body's centre from the left end
  const double cg = (mass * pos + m * body) / (mass + m);
  const double inertia = params[at.bar_inertia] + m * (body - cg) * (body - cg) +
                         mass * (cg - pos) * (cg - pos) +
                         m * params[at.body_cg_height] * params[at.body_cg_height] +
                         mass * params[at.added_mass_height] * params[at.added_mass_height];
  if (!(inertia > 0.0)) {
    return outOfDomain(names[at.added_mass], mass,
                       "makes the inertia about the combined centre <= 0");
  }
  return rollPlaneEquilibriumRefusal(params);
}

// Each point's values are read by row from its column of params (no copy).
std::unique_ptr<ModelBatch> RollPlaneModel::prepare(const Eigen::MatrixXd& params) const {
  if (params.rows() != nominal_.values.size()) {
    throw std::invalid_argument("RollPlaneModel::prepare: expected " +
                                std::to_string(nominal_.values.size()) + " parameter rows");
  }
  const int count = static_cast<int>(params.cols());
  for (int q = 0; q < count; ++q) {
    const std::string why = invalidReason(params.col(q));
    if (!why.empty()) {
      throw std::invalid_argument("RollPlaneModel::prepare: column " + std::to_string(q) + ": " +
                                  why);
    }
  }
  const std::vector<StaticEquilibrium> equilibria = solveStaticEquilibria(params);
  const RollPlaneFields<int>& at = rollPlaneRows();
  PointConstants c(count);
  using C = PointConstants;
  // tanh: c scale; linear: c; table: c / c_ref (the curve gives the force).
  double scale[2] = {1.0, 1.0};
  for (int i = 0; i < 2; ++i) {
    if (damper_ == DamperLaw::kTanh) scale[i] = tanh_scale_;
    if (damper_ == DamperLaw::kTable) scale[i] = 1.0 / curve_[i].referenceDamping();
  }
  const HorizontalMotion* motion = road_->horizontalMotion();
  bool elevated = motion && motion->accelerates();
  for (int q = 0; q < count; ++q) {
    const double* p = &params(0, q);
    const StaticEquilibrium& e = equilibria[q];
    const double length = p[at.bar_length], cg = e.combined_cg,
                 total = p[at.bar_mass] + p[at.added_mass];
    for (int i = 0; i < 2; ++i) {
      const double delta = e.spring_compression[i];
      c(q, C::kK + i) = p[at.spring_linear[i]];
      c(q, C::kK3 + i) = p[at.spring_cubic[i]];
      c(q, C::kThreeDelta + i) = 3.0 * delta;
      c(q, C::kThreeDeltaSq + i) = 3.0 * delta * delta;
      c(q, C::kDamping + i) = p[at.damping[i]] * scale[i];
      c(q, C::kTyre + i) = p[at.tyre_stiffness[i]];
      c(q, C::kInvUnsprung + i) = 1.0 / p[at.unsprung_mass[i]];
    }
    // I_cg = I + m (L/2 - e_b - D)^2 + M (D - d_CG)^2 (docs/method.md §1.4).
    const double position = p[at.added_mass_position];
    const double body = 0.5 * length - p[at.body_cg_offset];
    double inertia = p[at.bar_inertia] + p[at.bar_mass] * (body - cg) * (body - cg) +
                     p[at.added_mass] * (cg - position) * (cg - position);
    // J = I_cg + m h_b^2 + M h_M^2, S = m h_b + M h_M (docs/models.md).
    const double moment = p[at.bar_mass] * p[at.body_cg_height] +
                          p[at.added_mass] * p[at.added_mass_height];
    if (elevatedPoint(p)) {
      elevated = true;
      inertia += p[at.bar_mass] * p[at.body_cg_height] * p[at.body_cg_height] +
                 p[at.added_mass] * p[at.added_mass_height] * p[at.added_mass_height];
    }
    c(q, C::kInvTotalMass) = 1.0 / total;
    c(q, C::kRollGain) = length / inertia;
    c(q, C::kCg) = cg;
    c(q, C::kRearArm) = length - cg;
    c(q, C::kCgRatio) = cg / length;
    c(q, C::kInvLength) = 1.0 / length;
    c(q, C::kRollStatic) = e.roll_angle;
    // theta_s = atan(s): cos = 1 / sqrt(1 + s^2), sin = s cos (no library sin/cos).
    const double slope = (e.height[1] - e.height[0]) / length;
    const double cos_static = 1.0 / std::sqrt(1.0 + slope * slope);
    c(q, C::kCosStatic) = cos_static;
    c(q, C::kSinStatic) = slope * cos_static;
    c(q, C::kBar) = p[at.anti_roll_bar];
    c(q, C::kFirstMoment) = moment;
    c(q, C::kStaticMoment) = -moment * p[at.gravity] * slope;  // tan(phi_s) = -slope
    c(q, C::kGravity) = p[at.gravity];
    c(q, C::kTransfer) = (total * p[at.mount_height] +
                          (p[at.unsprung_mass[0]] + p[at.unsprung_mass[1]]) * p[at.wheel_radius]) /
                         length;
  }
  std::unique_ptr<RollPlaneReadings> r;
  if (readings_.as_states) {
    r = readingConstants(params, equilibria);
    r->elevated = elevated || (r->imu_height != 0.0).any();
  }
  return std::make_unique<RollPlaneBatch>(std::move(c), damper_, tanh_rate_, curve_, road_, elevated,
                                          std::move(r));
}

std::unique_ptr<RollPlaneReadings> RollPlaneModel::readingConstants(
    const Eigen::MatrixXd& params, const std::vector<StaticEquilibrium>& equilibria) const {
  const Eigen::Index count = params.cols();
  const RollPlaneFields<int>& at = rollPlaneRows();
  auto r = std::make_unique<RollPlaneReadings>();
  r->imu_fraction.resize(count);
  r->inv_length.resize(count);
  r->gravity.resize(count);
  r->roll_static.resize(count);
  r->rest_y.resize(count);
  r->rest_z.resize(count);
  r->imu_height.resize(count);
  r->travel_offset = Eigen::ArrayXXd::Zero(2, count);
  const bool tare = readings_.zero == ZeroConvention::kTare;
  std::vector<StaticEquilibrium> empty;
  if (tare) {
    // The sensors were zeroed on the empty vehicle: the same vehicle, no load.
    Eigen::MatrixXd unloaded = params;
    unloaded.row(at.added_mass).setZero();
    empty = solveStaticEquilibria(unloaded);
  }
  for (Eigen::Index q = 0; q < count; ++q) {
    const double* p = &params(0, q);
    const StaticEquilibrium& e = equilibria[static_cast<std::size_t>(q)];
    r->imu_fraction[q] = p[at.imu_position] / p[at.bar_length];
    r->inv_length[q] = 1.0 / p[at.bar_length];
    r->imu_height[q] = p[at.imu_height];
    r->gravity[q] = p[at.gravity];
    r->roll_static[q] = -e.roll_angle;
    r->rest_y[q] = tare ? 0.0 : p[at.gravity] * std::sin(-e.roll_angle);
    r->rest_z[q] = tare ? 0.0 : p[at.gravity] * std::cos(-e.roll_angle);
    for (int i = 0; i < 2 && tare; ++i) {
      // Extension positive: the load's extra compression reads negative.
      r->travel_offset(i, q) = e.spring_compression[i] -
                               empty[static_cast<std::size_t>(q)].spring_compression[i];
    }
  }
  return r;
}

std::vector<double> RollPlaneModel::breakpoints(double t0, double t1) const {
  return road_->breakpoints(t0, t1);
}

void RollPlaneModel::carryOver(const Eigen::VectorXd& from, const Eigen::VectorXd& to,
                               Eigen::ArrayXXd& y) const {
  Eigen::MatrixXd both(from.size(), 2);
  both.col(0) = from;
  both.col(1) = to;
  const std::vector<StaticEquilibrium> e = solveStaticEquilibria(both);
  const RollPlaneFields<int>& at = rollPlaneRows();
  for (int i = 0; i < 2; ++i) {
    const auto tyre = [&](int k) {
      const Eigen::VectorXd& p = k == 0 ? from : to;
      return (e[static_cast<std::size_t>(k)].load[i] + p[at.unsprung_mass[i]] * p[at.gravity]) /
             p[at.tyre_stiffness[i]];
    };
    y.row(i) += e[0].height[i] - e[1].height[i];
    y.row(2 + i) += tyre(1) - tyre(0);  // the unsprung mass sits at minus its tyre's compression
  }
}

}  // namespace pc_ekf
