// Full-car ride model: parameter checks and the batched right-hand side.
#include "pc_ekf/model/full_car_model.h"

#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <utility>

#include "pc_ekf/model/smooth_functions.h"

namespace pc_ekf {

namespace {

// A direct-mapped table of the thread's latest equilibria, keyed by the model
// and the exact bits of the parameter vector (a hit returns what the solve
// would: it is deterministic).
struct EquilibriumMemo {
  struct Slot {
    std::uint64_t model = 0;  // 0: empty
    Eigen::VectorXd params;
    FullCarEquilibrium equilibrium;
    std::string error;  // the solve's failure, if it failed
  };
  static constexpr std::size_t kSlots = 1024;
  std::array<Slot, kSlots> slots;

  static std::size_t slotOf(std::uint64_t model, const Eigen::Ref<const Eigen::VectorXd>& p) {
    std::uint64_t h = 1469598103934665603ull ^ model;  // FNV-1a over the bytes
    for (Eigen::Index i = 0; i < p.size(); ++i) {
      std::uint64_t bits;
      const double v = p[i];
      std::memcpy(&bits, &v, sizeof bits);
      for (int b = 0; b < 8; ++b) h = (h ^ ((bits >> (8 * b)) & 0xff)) * 1099511628211ull;
    }
    return static_cast<std::size_t>(h % kSlots);
  }
};

std::atomic<std::uint64_t> next_model_id{1};

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

class FullCarBatch : public ModelBatch {
 public:
  FullCarBatch(PointConstants c, DamperLaw law, double tanh_rate,
               std::shared_ptr<const ContactRoad> road)
      : c_(std::move(c)), p_(c_), law_(law), tanh_rate_(tanh_rate), road_(std::move(road)) {}
  FullCarBatch(const FullCarBatch&) = delete;
  FullCarBatch& operator=(const FullCarBatch&) = delete;

  int pointCount() const override { return static_cast<int>(c_.size()); }

  Eigen::ArrayXXd initialState() const override {
    return Eigen::ArrayXXd::Zero(14, pointCount());  // the static equilibrium
  }

  void derivatives(double t, const Eigen::ArrayXXd& y, Eigen::ArrayXXd& dydt) const override {
    if (y.rows() != 14 || y.cols() != pointCount()) {
      throw std::invalid_argument("FullCarModel: state batch must be 14 x pointCount()");
    }
    dydt.resize(14, y.cols());
    Eigen::Vector4d road;
    road_->heights(t, road);
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
    transposedDerivatives(p_, law_ == DamperLaw::kTanh, tanh_rate_, road.data(), y.data(),
                          dydt.data(), n);
  }

 private:
  PointConstants c_;
  ConstantPointers p_;
  DamperLaw law_;
  double tanh_rate_;
  std::shared_ptr<const ContactRoad> road_;
};

void setConstants(const FullCarParameters& p, const FullCarEquilibrium& e, double damper_scale,
                  Eigen::Index q, PointConstants& c) {
  using C = PointConstants;
  for (int i = 0; i < 4; ++i) {
    const int axle = FullCarParameters::axle(i);
    const double delta = e.spring_compression[i];
    c(q, C::kX + i) = p.cornerX(i);
    c(q, C::kY + i) = p.cornerY(i);
    c(q, C::kK + i) = p.spring_linear[axle];
    c(q, C::kK3 + i) = p.spring_cubic[axle];
    c(q, C::kThreeDelta + i) = 3.0 * delta;
    c(q, C::kThreeDeltaSq + i) = 3.0 * delta * delta;
    c(q, C::kDamping + i) = p.damping[axle] * damper_scale;
    c(q, C::kInvUnsprung + i) = 1.0 / p.unsprung_mass[axle];
  }
  c(q, C::kTyre) = p.tyre_stiffness;
  // M is a point mass at (x_M, y_M) at the height of O: it moves with z + x_M theta + y_M phi.
  const double m = p.added_mass, xm = p.addedMassX(), ym = p.addedMassY();
  Eigen::Matrix3d mb;
  // clang-format off
  mb << p.body_mass + m, m * xm,                        m * ym,
        m * xm,          p.pitch_inertia + m * xm * xm, m * xm * ym,
        m * ym,          m * xm * ym,                   p.roll_inertia + m * ym * ym;
  // clang-format on
  const Eigen::Matrix3d inv = mb.inverse();
  for (int r = 0; r < 3; ++r) {
    for (int col = 0; col < 3; ++col) c(q, C::kInvBodyMass + 3 * r + col) = inv(r, col);
  }
}

}  // namespace

FullCarModel::FullCarModel(const FullCarParameters& nominal,
                           std::shared_ptr<const ContactRoad> road)
    : nominal_(nominal),
      nominal_vector_(nominal.toVector()),
      id_(next_model_id++),
      h_(Eigen::MatrixXd::Zero(8, 14)),
      road_(std::move(road)) {
  if (!road_) throw std::invalid_argument("FullCarModel: no road input");
  if (road_->contactCount() != 4) {
    throw std::invalid_argument("FullCarModel: the road must have 4 contacts, got " +
                                std::to_string(road_->contactCount()));
  }
  const std::string why = invalidReason(nominal_vector_);
  if (!why.empty()) throw std::invalid_argument("FullCarModel: nominal parameters: " + why);
  if (nominal_.damper == DamperLaw::kTanh &&
      !(std::isfinite(nominal_.damper_tanh_scale) && std::isfinite(nominal_.damper_tanh_rate) &&
        nominal_.damper_tanh_scale >= 0.0 && nominal_.damper_tanh_rate >= 0.0)) {
    throw std::invalid_argument("FullCarModel: damper tanh scale and rate must be finite, >= 0");
  }
  // u_i = z + x_i theta + y_i phi - zu_i and its rate, with the nominal geometry.
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
  const std::string why = description().parameters().violation(params);
  if (!why.empty()) return why;
  try {
    equilibrium(params);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

FullCarEquilibrium FullCarModel::equilibrium(const Eigen::Ref<const Eigen::VectorXd>& params) const {
  thread_local EquilibriumMemo memo;
  EquilibriumMemo::Slot& slot = memo.slots[EquilibriumMemo::slotOf(id_, params)];
  if (slot.model != id_ || slot.params.size() != params.size() ||
      std::memcmp(slot.params.data(), params.data(), sizeof(double) * params.size()) != 0) {
    slot.model = id_;
    slot.params = params;
    slot.error.clear();
    try {
      slot.equilibrium = solveFullCarEquilibrium(FullCarParameters::fromVector(params, nominal_));
    } catch (const std::runtime_error& e) {
      slot.error = e.what();
    }
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
  for (Eigen::Index q = 0; q < params.cols(); ++q) {
    const std::string prefix = "FullCarModel::prepare: column " + std::to_string(q) + ": ";
    const std::string why = description().parameters().violation(params.col(q));
    if (!why.empty()) throw std::invalid_argument(prefix + why);
    const FullCarParameters p = FullCarParameters::fromVector(params.col(q), nominal_);
    FullCarEquilibrium e;
    try {
      e = equilibrium(params.col(q));
    } catch (const std::runtime_error& error) {
      throw std::invalid_argument(prefix + error.what());
    }
    setConstants(p, e, scale, q, points);
  }
  return std::make_unique<FullCarBatch>(std::move(points), nominal_.damper,
                                        nominal_.damper_tanh_rate, road_);
}

std::vector<double> FullCarModel::breakpoints(double t0, double t1) const {
  return road_->breakpoints(t0, t1);
}

}  // namespace pc_ekf
