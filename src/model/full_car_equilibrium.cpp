// Static equilibrium of the full car: statically indeterminate (four corners,
// three body equations), so the body pose and the wheel heights are solved
// together. Unknowns X = [z_s, theta_s, phi_s, zu_fl, zu_fr, zu_rl, zu_rr].
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "pc_ekf/model/full_car_model.h"

namespace pc_ekf {

namespace {

using Vector7 = Eigen::Matrix<double, 7, 1>;
using Matrix7 = Eigen::Matrix<double, 7, 7>;

struct Setup {
  double x[4], y[4], k[4], k3[4], unsprung_weight[4];
  double tyre;
  double body_load[3];  // g [m_s + M, M x_M, M y_M]
  // Heights and bars (docs/models.md): k_a of each corner's axle, and
  // g S = g (m_s h_b + M h_M), the elevated masses' moment per unit tilt.
  double bar[4];
  double tilt_moment;
  bool elevated;  // bars or S: the general residuals (else today's, bit for bit)
};

Setup setupOf(const FullCarColumn& p) {
  const FullCarFields<int>& at = p.at();
  Setup s;
  for (int c = 0; c < 4; ++c) {
    const int axle = FullCarParameters::axle(c);
    s.x[c] = p.cornerX(c);
    s.y[c] = p.cornerY(c);
    s.k[c] = p[at.spring_linear[axle]];
    s.k3[c] = p[at.spring_cubic[axle]];
    s.unsprung_weight[c] = p[at.unsprung_mass[axle]] * p[at.gravity];
  }
  s.tyre = p[at.tyre_stiffness];
  const double m = p[at.added_mass], g = p[at.gravity];
  s.body_load[0] = (p[at.body_mass] + m) * g;
  s.body_load[1] = m * p.addedMassX() * g;
  s.body_load[2] = m * p.addedMassY() * g;
  for (int c = 0; c < 4; ++c) s.bar[c] = p[at.anti_roll_bar[FullCarParameters::axle(c)]];
  s.tilt_moment = g * (p[at.body_mass] * p[at.body_cg_height] + m * p[at.added_mass_height]);
  s.elevated = s.tilt_moment != 0.0 || s.bar[0] != 0.0 || s.bar[2] != 0.0;
  return s;
}

double compression(const Setup& s, const Vector7& x, int c) {
  return x[3 + c] - (x[0] + s.x[c] * x[1] + s.y[c] * x[2]);
}

// With heights or anti-roll bars (docs/models.md): each corner's load is its
// spring's force plus its axle's bar, W_c = F_K(delta_c) + k_a (delta_c -
// delta_partner) (the bar untwisted when both springs are equally
// compressed), the body equations
//   sum W = g (m_s + M),  sum W x = g (M x_M - S tan theta_s),
//   sum W y = g (M y_M - S tan phi_s)
// with tan theta_s = X[1] and tan phi_s = X[2] (the slopes of the corner
// plane, as the small-angle corner heights take them), and each wheel
// W_c + m_u g = -k_t zu_c (the bar acts on the unsprung masses oppositely).
Vector7 elevatedResiduals(const Setup& s, const Vector7& x, bool cubic, Matrix7* j) {
  Vector7 r;
  for (int i = 0; i < 3; ++i) r[i] = -s.body_load[i];
  r[1] += s.tilt_moment * x[1];
  r[2] += s.tilt_moment * x[2];
  if (j) {
    j->setZero();
    (*j)(1, 1) = s.tilt_moment;
    (*j)(2, 2) = s.tilt_moment;
  }
  double d[4], slope[4];
  for (int c = 0; c < 4; ++c) {
    d[c] = compression(s, x, c);
    const double k3 = cubic ? s.k3[c] : 0.0;
    slope[c] = s.k[c] + 3.0 * k3 * d[c] * d[c];
  }
  for (int c = 0; c < 4; ++c) {
    const int partner = c ^ 1;  // the other corner of the axle
    const double k3 = cubic ? s.k3[c] : 0.0;
    const double load = s.k[c] * d[c] + k3 * d[c] * d[c] * d[c] + s.bar[c] * (d[c] - d[partner]);
    const double lever[3] = {1.0, s.x[c], s.y[c]};
    for (int i = 0; i < 3; ++i) r[i] += load * lever[i];
    r[3 + c] = load + s.unsprung_weight[c] + s.tyre * x[3 + c];
    if (!j) continue;
    // d delta_c / dX = [-1, -x_c, -y_c, e_c]; the load's derivative:
    // (slope_c + k_a) d delta_c - k_a d delta_partner.
    double dl[7] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    const double own = slope[c] + s.bar[c];
    dl[0] = -own + s.bar[c];
    dl[1] = -own * s.x[c] + s.bar[c] * s.x[partner];
    dl[2] = -own * s.y[c] + s.bar[c] * s.y[partner];
    dl[3 + c] = own;
    dl[3 + partner] = -s.bar[c];
    for (int col = 0; col < 7; ++col) {
      for (int i = 0; i < 3; ++i) (*j)(i, col) += dl[col] * lever[i];
      (*j)(3 + c, col) += dl[col];
    }
    (*j)(3 + c, 3 + c) += s.tyre;
  }
  return r;
}

// Residuals R(X) (body force and moments, then the wheels) and, when j is
// given, their Jacobian. cubic = false drops k3 (the linear start).
Vector7 residuals(const Setup& s, const Vector7& x, bool cubic, Matrix7* j) {
  if (s.elevated) return elevatedResiduals(s, x, cubic, j);
  Vector7 r;
  for (int i = 0; i < 3; ++i) r[i] = -s.body_load[i];
  if (j) j->setZero();
  for (int c = 0; c < 4; ++c) {
    const double d = compression(s, x, c);
    const double k3 = cubic ? s.k3[c] : 0.0;
    const double force = s.k[c] * d + k3 * d * d * d;
    const double lever[3] = {1.0, s.x[c], s.y[c]};
    for (int i = 0; i < 3; ++i) r[i] += force * lever[i];
    r[3 + c] = force + s.unsprung_weight[c] + s.tyre * x[3 + c];
    if (!j) continue;
    const double slope = s.k[c] + 3.0 * k3 * d * d;
    // d delta_c / dX = [-1, -x_c, -y_c, e_c]
    double dd[7] = {-1.0, -s.x[c], -s.y[c], 0.0, 0.0, 0.0, 0.0};
    dd[3 + c] = 1.0;
    for (int col = 0; col < 7; ++col) {
      for (int i = 0; i < 3; ++i) (*j)(i, col) += slope * lever[i] * dd[col];
      (*j)(3 + c, col) += slope * dd[col];
    }
    (*j)(3 + c, 3 + c) += s.tyre;
  }
  return r;
}

[[noreturn]] void fail(const std::string& why, int iterations) {
  std::ostringstream os;
  os << "full-car static equilibrium: " << why << " after " << iterations << " Newton iterations";
  throw std::runtime_error(os.str());
}

// The Newton step's linear solve: Gaussian elimination with partial
// pivoting, written out for 7 x 7 (the Jacobian is a stiffness matrix, well
// conditioned). Every collocation point's equilibrium is solved at every
// sample (the admissibility check): Eigen's full pivoting took 30 % of
// full_car_live.yaml's run, its general partial-pivoting kernel 18 %.
Vector7 linearSolve(const Matrix7& j, const Vector7& r) {
  double a[7][8];
  for (int row = 0; row < 7; ++row) {
    for (int col = 0; col < 7; ++col) a[row][col] = j(row, col);
    a[row][7] = r[row];
  }
  for (int col = 0; col < 7; ++col) {
    int pivot = col;
    for (int row = col + 1; row < 7; ++row) {
      if (std::abs(a[row][col]) > std::abs(a[pivot][col])) pivot = row;
    }
    if (pivot != col) std::swap(a[pivot], a[col]);
    const double inverse = 1.0 / a[col][col];  // 0: inf/NaN, refused by the caller
    for (int row = col + 1; row < 7; ++row) {
      const double f = a[row][col] * inverse;
      for (int k = col + 1; k < 8; ++k) a[row][k] -= f * a[col][k];
    }
  }
  Vector7 x;
  for (int row = 6; row >= 0; --row) {
    double v = a[row][7];
    for (int k = row + 1; k < 7; ++k) v -= a[row][k] * x[k];
    x[row] = v / a[row][row];
  }
  return x;
}

// From `start` when given (a neighbouring point's solution: three Newton
// steps instead of a linear solve and five), else from the linear-spring
// solution.
FullCarEquilibrium solve(const FullCarColumn& p, const Vector7* start = nullptr) {
  const Setup s = setupOf(p);
  Matrix7 j;
  Vector7 x;
  if (start) {
    x = *start;
  } else {
    // Linear springs: R is affine, so one solve from 0 is exact.
    const Vector7 zero = Vector7::Zero();
    const Vector7 r0 = residuals(s, zero, false, &j);
    x = -linearSolve(j, r0);
    if (!x.allFinite()) fail("non-finite linear-spring solution", 0);
  }
  int it = 0;
  bool converged = false;
  constexpr int kMaxIterations = 100;
  while (!converged) {
    if (it == kMaxIterations) fail("no convergence", it);
    const Vector7 r = residuals(s, x, true, &j);
    if (!r.allFinite()) fail("non-finite residual", it);
    const Vector7 step = -linearSolve(j, r);
    if (!step.allFinite()) fail("non-finite Newton step", it);
    ++it;
    const double scale = std::max(x.cwiseAbs().maxCoeff(), std::numeric_limits<double>::min());
    if (step.cwiseAbs().maxCoeff() <= 1e-12 * scale) {
      x += step;  // quadratic convergence: what remains is round-off
      converged = true;
      continue;
    }
    if (step.cwiseAbs().maxCoeff() <= 1e-8 * scale) {
      x += step;  // close: the residual may already be at round-off
      continue;
    }
    // Halve the step until the residual decreases (the cubic springs can make
    // a full step overshoot far from the solution).
    const double norm = r.norm();
    double lambda = 1.0;
    for (;;) {
      const Vector7 trial = x + lambda * step;
      const double trial_norm = residuals(s, trial, true, nullptr).norm();
      if (trial_norm < norm) {
        x = trial;
        break;
      }
      lambda *= 0.5;
      if (lambda < 1e-12) fail("line search stalled", it);
    }
  }
  FullCarEquilibrium e;
  e.heave = x[0];
  e.pitch = x[1];
  e.roll = x[2];
  e.iterations = it;
  for (int c = 0; c < 4; ++c) {
    const double d = compression(s, x, c);
    e.wheel_height[c] = x[3 + c];
    e.spring_compression[c] = d;
    e.load[c] = s.k[c] * d + s.k3[c] * d * d * d;
  }
  if (s.elevated) {
    // The load the wheel carries: spring plus bar.
    double spring[4];
    for (int c = 0; c < 4; ++c) spring[c] = e.load[c];
    for (int c = 0; c < 4; ++c) {
      e.load[c] = spring[c] + s.bar[c] * (e.spring_compression[c] - e.spring_compression[c ^ 1]);
    }
  }
  return e;
}

}  // namespace

FullCarEquilibrium solveFullCarEquilibrium(const FullCarColumn& p) { return solve(p); }

FullCarEquilibrium solveFullCarEquilibriumFrom(const FullCarColumn& p,
                                               const FullCarEquilibrium& start) {
  Vector7 x;
  x << start.heave, start.pitch, start.roll, start.wheel_height[0], start.wheel_height[1],
      start.wheel_height[2], start.wheel_height[3];
  try {
    if (x.allFinite()) return solve(p, &x);
  } catch (const std::runtime_error&) {
    // A start too far for Newton: the solve from the linear springs decides.
  }
  return solve(p);
}

FullCarEquilibriumKey fullCarEquilibriumKey(const FullCarColumn& p) {
  const Setup s = setupOf(p);
  FullCarEquilibriumKey key;
  std::size_t i = 0;
  for (const double* group : {s.x, s.y, s.k, s.k3, s.unsprung_weight, s.bar}) {
    for (int c = 0; c < 4; ++c) key[i++] = group[c];
  }
  key[i++] = s.tyre;
  for (double b : s.body_load) key[i++] = b;
  key[i++] = s.tilt_moment;
  key[i++] = s.elevated ? 1.0 : 0.0;
  return key;
}

FullCarEquilibrium solveFullCarEquilibrium(const FullCarParameters& p) {
  const Eigen::VectorXd v = p.toVector();
  return solve(FullCarColumn(v.data()));
}

std::vector<FullCarEquilibrium> solveFullCarEquilibria(const std::vector<FullCarParameters>& ps) {
  std::vector<FullCarEquilibrium> out;
  out.reserve(ps.size());
  for (const FullCarParameters& p : ps) out.push_back(solveFullCarEquilibrium(p));
  return out;
}

}  // namespace pc_ekf
