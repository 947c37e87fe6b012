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
// The elevated masses' first moment S and dW_2/dt = g S / L.
double elevatedMoment(const double* p, const RollPlaneFields<int>& at) {
  return p[at.bar_mass] * p[at.body_cg_height] + p[at.added_mass] * p[at.added_mass_height];
}

// For a tilt t, the loads W_i(t) and the compressions d_i solving the spring
// and bar equations F_Ki(d_i) +- k_a (d_1 - d_2) = W_i(t) (the gradient of a
// strictly convex energy: one solution, found by Newton halving its step
// until the residual falls), from the d given; returns g(t) = L t - (h_1 - h_2)
// and its slope g'(t) (negative: the tilt grows by itself, an unstable point).
struct TiltResidual {
  const double* p;
  const RollPlaneFields<int>& at;
  double combined_cg, weight, shift;
  double operator()(double t, double d[2], double w[2], double* slope_out) const {
    const double g = p[at.gravity], length = p[at.bar_length], bar = p[at.anti_roll_bar];
    w[0] = weight * (length - combined_cg) / length - shift * t;
    w[1] = weight * combined_cg / length + shift * t;
    double k[2], k3[2];
    for (int i = 0; i < 2; ++i) {
      k[i] = p[at.spring_linear[i]];
      k3[i] = p[at.spring_cubic[i]];
    }
    const auto residual = [&](const double x[2], double r[2]) {
      const double twist = bar * (x[0] - x[1]);
      r[0] = k[0] * x[0] + k3[0] * x[0] * x[0] * x[0] + twist - w[0];
      r[1] = k[1] * x[1] + k3[1] * x[1] * x[1] * x[1] - twist - w[1];
      return std::hypot(r[0], r[1]);
    };
    double r[2], s[2];
    double norm = residual(d, r);
    for (int it = 0; it < 200 && norm > 0.0; ++it) {
      for (int i = 0; i < 2; ++i) s[i] = k[i] + 3.0 * k3[i] * d[i] * d[i];
      const double a = s[0] + bar, b = -bar, c = s[1] + bar, det = a * c - b * b;
      const double step[2] = {(c * r[0] - b * r[1]) / det, (a * r[1] - b * r[0]) / det};
      double lambda = 1.0, trial[2], rt[2], trial_norm = norm;
      for (int h = 0; h < 60; ++h, lambda *= 0.5) {
        trial[0] = d[0] - lambda * step[0];
        trial[1] = d[1] - lambda * step[1];
        trial_norm = residual(trial, rt);
        if (trial_norm < norm) break;
      }
      if (!(trial_norm < norm)) break;  // round-off: no step lowers it
      const bool small = std::abs(d[0] - trial[0]) <= 1e-15 * (std::abs(d[0]) + 1e-300) &&
                         std::abs(d[1] - trial[1]) <= 1e-15 * (std::abs(d[1]) + 1e-300);
      d[0] = trial[0];
      d[1] = trial[1];
      r[0] = rt[0];
      r[1] = rt[1];
      norm = trial_norm;
      if (small) break;
    }
    for (int i = 0; i < 2; ++i) s[i] = k[i] + 3.0 * k3[i] * d[i] * d[i];
    // The springs' and bar's roll compliance d(d_1 - d_2)/d(W_1 - W_2) * 2.
    const double springs = (s[0] + s[1]) / (s[0] * s[1] + bar * (s[0] + s[1]));
    const double tyres = 1.0 / p[at.tyre_stiffness[0]] + 1.0 / p[at.tyre_stiffness[1]];
    if (slope_out) *slope_out = length - shift * (springs + tyres);
    double height[2];
    for (int i = 0; i < 2; ++i) {
      height[i] = -(d[i] + (w[i] + p[at.unsprung_mass[i]] * g) / p[at.tyre_stiffness[i]]);
    }
    return length * t - (height[0] - height[1]);
  }
};

[[noreturn]] void throwUnstable(double moment, double bar, const char* why) {
  throw std::runtime_error(
      std::string("static equilibrium: no stable equilibrium with heights and anti-roll bar (S = ") +
      std::to_string(moment) + " kg m, k_a = " + std::to_string(bar) + " N/m): " + why);
}

// The fallback when Newton on (delta_1, delta_2, t) fails or ends at an
// unstable point: g(t) = L t - (h_1 - h_2) is continuous, and when the
// tyres alone hold the moment (L > g S / L (1/k_t1 + 1/k_t2)) it runs from
// -inf to +inf, so a bracket widened from the start's tilt holds a root where
// g crosses upwards (g' >= 0: stable); bisection with Newton steps inside the
// bracket finds it. Without that margin g falls everywhere: no stable point.
void bracketTilt(const double* p, StaticEquilibrium& e, double t0, double moment) {
  const RollPlaneFields<int>& at = rollPlaneRows();
  const double length = p[at.bar_length], bar = p[at.anti_roll_bar];
  const double shift = p[at.gravity] * moment / length;
  const double tyres = 1.0 / p[at.tyre_stiffness[0]] + 1.0 / p[at.tyre_stiffness[1]];
  if (!(length - shift * tyres > 0.0)) {
    throwUnstable(moment, bar, "the tyres' roll stiffness does not carry the elevated moment");
  }
  const TiltResidual g{p, at, e.combined_cg, (p[at.bar_mass] + p[at.added_mass]) * p[at.gravity],
                       shift};
  double d[2] = {e.spring_compression[0], e.spring_compression[1]}, w[2], slope = 0.0;
  if (!std::isfinite(t0)) t0 = 0.0;
  // A bracket lo < hi with g(lo) < 0 <= g(hi), widened from t0 on the side
  // where the root lies (g(t0) > 0: below; < 0: above).
  const double g0 = g(t0, d, w, &slope);
  double lo = t0, hi = t0, t = t0;
  if (!(g0 == 0.0 && slope > 0.0)) {
    const double below = g0 >= 0.0 ? -1.0 : 1.0;
    double width = 1e-3, far = g0;
    for (int it = 0; it < 200 && (below < 0.0 ? !(far < 0.0) : !(far >= 0.0)); ++it) {
      width *= 2.0;
      far = g(t0 + below * width, d, w, nullptr);
    }
    if (below < 0.0) lo = t0 - width; else hi = t0 + width;
    if (below < 0.0 ? !(far < 0.0) : !(far >= 0.0)) {
      throwUnstable(moment, bar, "no tilt brackets it");
    }
    t = 0.5 * (lo + hi);
    for (int it = 0; it < 400 && hi - lo > 1e-15 * (1.0 + std::abs(t)); ++it) {
      const double r = g(t, d, w, &slope);
      if (r < 0.0) lo = t; else hi = t;
      if (r == 0.0) break;
      const double newton = t - r / slope;
      t = (slope > 0.0 && newton > lo && newton < hi) ? newton : 0.5 * (lo + hi);
    }
  }
  g(t, d, w, &slope);
  if (!(slope > 0.0) || !std::isfinite(d[0]) || !std::isfinite(d[1])) {
    throwUnstable(moment, bar, "the springs and bar do not restore the tilt");
  }
  for (int i = 0; i < 2; ++i) {
    e.spring_compression[i] = d[i];
    e.load[i] = w[i];
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
// The point must be stable (the Jacobian's determinant > 0: a small tilt is
// restored); when Newton fails or ends elsewhere, bracketTilt() solves it or
// says that there is no stable point.
void solveWithHeights(const double* p, StaticEquilibrium& e, const Eigen::Vector3d* start = nullptr) {
  const RollPlaneFields<int>& at = rollPlaneRows();
  const double g = p[at.gravity], length = p[at.bar_length], bar = p[at.anti_roll_bar];
  const double moment = elevatedMoment(p, at);
  const double weight = (p[at.bar_mass] + p[at.added_mass]) * g;
  const double shift = g * moment / length;  // dW_2/dt
  double w[2];
  const auto loads = [&](double t) {
    w[0] = weight * (length - e.combined_cg) / length - shift * t;
    w[1] = weight * e.combined_cg / length + shift * t;
  };
  const double t0 = (e.height[0] - e.height[1]) / length;
  // From a neighbouring point's solution when given (a filter's steps from
  // one point: two Newton steps instead of five), else from the solution
  // without heights and bar.
  Eigen::Vector3d x = start ? *start : Eigen::Vector3d(e.spring_compression[0], e.spring_compression[1], t0);
  bool converged = false;
  double determinant = 0.0;
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
    // Closed-form 3 x 3 inverse (cofactors): a pivoted LU costs several times more,
    // and Newton's residual, not the step's round-off, decides convergence.
    determinant = j.determinant();
    const Eigen::Vector3d step = j.inverse() * r;
    x -= step;
    if (!x.allFinite()) break;
    // Quadratic convergence: a step of 1e-14 (m; rad) leaves round-off.
    converged = step.cwiseAbs().maxCoeff() <= 1e-14;
  }
  // The spring block's determinant is > 0, so the sign of the whole one is g'(t)'s.
  if (!converged || !(determinant > 0.0)) {
    bracketTilt(p, e, t0, moment);
    return;
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
  // A filter's columns are a point and steps from it, often the point itself
  // again: a column equal to the first takes its solution.
  if (n > 1) {
    std::vector<Eigen::Index> distinct{0};
    std::vector<bool> same(n, false);
    for (Eigen::Index q = 1; q < params.cols(); ++q) {
      same[static_cast<std::size_t>(q)] = params.col(q) == params.col(0);
      if (!same[static_cast<std::size_t>(q)]) distinct.push_back(q);
    }
    if (distinct.size() < n) {
      const std::vector<StaticEquilibrium> solved = solveStaticEquilibria(params(Eigen::all, distinct));
      std::vector<StaticEquilibrium> es(n);
      std::size_t k = 0;
      for (std::size_t q = 0; q < n; ++q) es[q] = same[q] ? solved.front() : solved[k++];
      return es;
    }
  }
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
  Eigen::Vector3d start;
  bool have_start = false;
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
      // The first elevated column's solution starts the others' Newton.
      solveWithHeights(p, e, have_start ? &start : nullptr);
      for (int i = 0; i < 2; ++i) {
        e.height[i] =
            -(e.spring_compression[i] +
              (e.load[i] + p[at.unsprung_mass[i]] * p[at.gravity]) / p[at.tyre_stiffness[i]]);
      }
      if (!have_start) {
        start = Eigen::Vector3d(e.spring_compression[0], e.spring_compression[1],
                                (e.height[0] - e.height[1]) / p[at.bar_length]);
        have_start = true;
      }
    }
    e.roll_angle = std::atan((e.height[1] - e.height[0]) / p[at.bar_length]);
    if (!std::isfinite(e.roll_angle)) {
      throw std::runtime_error("static equilibrium: non-finite roll angle");
    }
  }
  return es;
}

std::string rollPlaneEquilibriumRefusal(const Eigen::Ref<const Eigen::VectorXd>& params) {
  const RollPlaneFields<int>& at = rollPlaneRows();
  const double* p = params.data();
  if (p[at.body_cg_height] == 0.0 && p[at.added_mass_height] == 0.0) return "";  // S = 0: stable
  const double length = p[at.bar_length], bar = p[at.anti_roll_bar];
  const double moment = elevatedMoment(p, at);
  const double shift = p[at.gravity] * moment / length;
  const double tyres = 1.0 / p[at.tyre_stiffness[0]] + 1.0 / p[at.tyre_stiffness[1]];
  const double k1 = p[at.spring_linear[0]], k2 = p[at.spring_linear[1]];
  // The linear rates bound the compliance from above (k3 >= 0 only stiffens):
  // with this margin g(t) rises everywhere, one stable point that the solve finds.
  const double springs = (k1 + k2) / (k1 * k2 + bar * (k1 + k2));
  if (length - shift * (tyres + springs) > 0.0) return "";
  if (!(length - shift * tyres > 0.0)) {
    return "no stable static equilibrium: the tyres' roll stiffness does not carry the elevated "
           "masses' moment (S = " + std::to_string(moment) + " kg m)";
  }
  try {
    solveStaticEquilibria(params);
  } catch (const std::runtime_error& error) {
    return error.what();
  }
  return "";
}

StaticEquilibrium solveStaticEquilibrium(const VehicleParameters& p) {
  return solveStaticEquilibria(p.toVector()).front();
}

}  // namespace pc_ekf
