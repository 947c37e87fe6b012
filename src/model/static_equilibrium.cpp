// Static equilibrium of the roll-plane model (docs/method.md §1.3).
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include "pc_ekf/model/roll_plane_model.h"
#include "pc_ekf/model/smooth_functions.h"

namespace pc_ekf {

namespace {

constexpr double kIterating = 0.0, kConverged = 1.0, kFailed = 2.0;

// One Newton step for every spring still iterating (branch-free, so it
// vectorises: compiled for x86-64-v3 and the baseline); a finished spring keeps
// its value and state. Returns how many are still iterating.
__attribute__((target_clones("arch=x86-64-v3", "default"))) double newtonSweep(
    const double* __restrict k, const double* __restrict k3, const double* __restrict a,
    double* __restrict d, double* __restrict state, std::size_t count) {
  using smooth_detail::select;
  double iterating = 0.0;
  for (std::size_t j = 0; j < count; ++j) {
    const double x = d[j];
    const double step = (k[j] * x + k3[j] * x * x * x - a[j]) / (k[j] + 3.0 * k3[j] * x * x);
    const double next = x - step;
    const bool active = state[j] == kIterating;
    const bool converged = (std::abs(step) <= 1e-15 * std::abs(next)) | (step == 0.0);
    const bool finite = std::abs(next) <= 1.7976931348623157e308;  // false for NaN, Inf
    d[j] = select(active, next, x);
    state[j] = select(active, select(converged, kConverged, select(finite, kIterating, kFailed)),
                      state[j]);
    iterating += select(state[j] == kIterating, 1.0, 0.0);
  }
  return iterating;
}

// Solves k d + k3 d^3 = w for every spring at once. For k > 0, k3 >= 0 the law
// is odd, increasing and convex for d > 0, so Newton from an over-estimate
// decreases monotonically to the root. The solves advance in lockstep, each
// stopping on its own criterion (so each gives what it would alone), and
// vectorised across springs: prepare() solves 2Q of them at once.
void springCompressions(const double* k, const double* k3, const double* w, double* out,
                        std::size_t count) {
  std::vector<double> a(count), d(count), state(count, kIterating);
  for (std::size_t j = 0; j < count; ++j) {
    a[j] = std::abs(w[j]);
    d[j] = a[j] / k[j];
    // Both over-estimate the root. The cube root is only needed when it can be
    // the smaller (with a margin far above round-off, so the start is unchanged).
    if (k3[j] > 0.0 && d[j] * d[j] * d[j] * k3[j] > a[j] * (1.0 - 1e-12)) {
      d[j] = std::min(d[j], std::cbrt(a[j] / k3[j]));
    }
    if (!std::isfinite(d[j])) state[j] = kFailed;
  }
  for (int it = 0; it < 100; ++it) {
    if (newtonSweep(k, k3, a.data(), d.data(), state.data(), count) == 0.0) break;
  }
  for (std::size_t j = 0; j < count; ++j) {
    if (state[j] == kConverged) {
      out[j] = std::copysign(d[j], w[j]);
      continue;
    }
    std::ostringstream os;
    os << "static equilibrium: Newton did not converge for spring k = " << k[j]
       << ", k3 = " << k3[j] << ", load = " << w[j];
    throw std::runtime_error(os.str());
  }
}

// Heights or an anti-roll bar (docs/models.md): the loads W_i (spring plus
// bar) depend on the tilt, t = tan(phi_s) = (h_1 - h_2) / L, through the
// elevated masses' first moment S, and the bar couples the springs. Newton on
// (delta_1, delta_2, t) from the solution without them, for the equations
//   F_K1(d1) + k_a (d1 - d2) = W_1(t),  F_K2(d2) - k_a (d1 - d2) = W_2(t),
//   L t = h_1 - h_2,  h_i = -(d_i + (W_i + m_ti g) / k_ti),
// W_1 = g (m + M) (L - D) / L - g S t / L and W_2 = g (m + M) - W_1, i.e.
// sum W_i = g (m + M) and (W_1 - W_2) L / 2 = g (M y_M - S t).
void solveWithHeights(const double* p, StaticEquilibrium& e) {
  const RollPlaneFields<int>& at = rollPlaneRows();
  const double g = p[at.gravity], length = p[at.bar_length], bar = p[at.anti_roll_bar];
  const double moment =
      p[at.bar_mass] * p[at.body_cg_height] + p[at.added_mass] * p[at.added_mass_height];
  const double weight = (p[at.bar_mass] + p[at.added_mass]) * g;
  const double shift = g * moment / length;  // dW_2/dt
  double w[2];
  const auto loads = [&](double t) {
    w[0] = weight * (length - e.combined_cg) / length - shift * t;
    w[1] = weight * e.combined_cg / length + shift * t;
  };
  Eigen::Vector3d x(e.spring_compression[0], e.spring_compression[1],
                    (e.height[0] - e.height[1]) / length);
  bool converged = false;
  for (int it = 0; it < 100 && !converged; ++it) {
    loads(x[2]);
    double force[2], slope[2], height[2];
    for (int i = 0; i < 2; ++i) {
      const double k = p[at.spring_linear[i]], k3 = p[at.spring_cubic[i]], d = x[i];
      force[i] = k * d + k3 * d * d * d;
      slope[i] = k + 3.0 * k3 * d * d;
      height[i] = -(d + (w[i] + p[at.unsprung_mass[i]] * g) / p[at.tyre_stiffness[i]]);
    }
    const double twist = bar * (x[0] - x[1]);
    const Eigen::Vector3d r(force[0] + twist - w[0], force[1] - twist - w[1],
                            length * x[2] - (height[0] - height[1]));
    Eigen::Matrix3d j;
    j << slope[0] + bar, -bar, shift, -bar, slope[1] + bar, -shift, 1.0, -1.0,
        length - shift * (1.0 / p[at.tyre_stiffness[0]] + 1.0 / p[at.tyre_stiffness[1]]);
    const Eigen::Vector3d step = j.partialPivLu().solve(r);
    x -= step;
    if (!x.allFinite()) break;
    // Quadratic convergence: a step of 1e-14 (m; rad) leaves round-off.
    converged = step.cwiseAbs().maxCoeff() <= 1e-14;
  }
  if (!converged) {
    throw std::runtime_error(
        "static equilibrium: Newton did not converge with heights and anti-roll bar (S = " +
        std::to_string(moment) + " kg m, k_a = " + std::to_string(bar) + " N/m)");
  }
  loads(x[2]);
  for (int i = 0; i < 2; ++i) {
    e.spring_compression[i] = x[i];
    e.load[i] = w[i];  // spring plus bar: what the unsprung mass carries
  }
}

}  // namespace

std::vector<StaticEquilibrium> solveStaticEquilibria(const Eigen::MatrixXd& params) {
  const RollPlaneFields<int>& at = rollPlaneRows();
  const std::size_t n = static_cast<std::size_t>(params.cols());
  std::vector<StaticEquilibrium> es(n);
  std::vector<double> k(2 * n), k3(2 * n), w(2 * n), d(2 * n);
  for (std::size_t j = 0; j < n; ++j) {
    const double* p = &params(0, static_cast<Eigen::Index>(j));
    StaticEquilibrium& e = es[j];
    const double total = p[at.bar_mass] + p[at.added_mass];
    const double length = p[at.bar_length];
    e.combined_cg =
        (p[at.added_mass] * p[at.added_mass_position] +
         p[at.bar_mass] * (0.5 * length - p[at.body_cg_offset])) /
        total;
    const double weight = total * p[at.gravity];
    // W_1 from (L - D) rather than weight - W_2: same value, exactly symmetric at D = L/2.
    e.load[0] = weight * (length - e.combined_cg) / length;
    e.load[1] = weight * e.combined_cg / length;
    for (int i = 0; i < 2; ++i) {
      k[2 * j + i] = p[at.spring_linear[i]];
      k3[2 * j + i] = p[at.spring_cubic[i]];
      w[2 * j + i] = e.load[i];
    }
  }
  springCompressions(k.data(), k3.data(), w.data(), d.data(), 2 * n);
  for (std::size_t j = 0; j < n; ++j) {
    const double* p = &params(0, static_cast<Eigen::Index>(j));
    StaticEquilibrium& e = es[j];
    for (int i = 0; i < 2; ++i) {
      e.spring_compression[i] = d[2 * j + i];
      const double tyre =
          (e.load[i] + p[at.unsprung_mass[i]] * p[at.gravity]) / p[at.tyre_stiffness[i]];
      e.height[i] = -(e.spring_compression[i] + tyre);
    }
    const bool elevated = p[at.body_cg_height] != 0.0 || p[at.added_mass_height] != 0.0;
    if (elevated || p[at.anti_roll_bar] != 0.0) {
      solveWithHeights(p, e);
      for (int i = 0; i < 2; ++i) {
        e.height[i] =
            -(e.spring_compression[i] +
              (e.load[i] + p[at.unsprung_mass[i]] * p[at.gravity]) / p[at.tyre_stiffness[i]]);
      }
    }
    e.roll_angle = std::atan((e.height[1] - e.height[0]) / p[at.bar_length]);
    if (!std::isfinite(e.roll_angle)) {
      throw std::runtime_error("static equilibrium: non-finite roll angle");
    }
  }
  return es;
}

StaticEquilibrium solveStaticEquilibrium(const VehicleParameters& p) {
  return solveStaticEquilibria(p.toVector()).front();
}

}  // namespace pc_ekf
