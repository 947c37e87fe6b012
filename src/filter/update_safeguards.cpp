#include "pc_ekf/filter/update_safeguards.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace pc_ekf {

std::string toString(SupportRule r) { return r == SupportRule::kDamp ? "damp" : "ignore"; }

SupportRule supportRuleFromString(const std::string& s) {
  if (s == "damp") return SupportRule::kDamp;
  if (s == "ignore") return SupportRule::kIgnore;
  throw std::invalid_argument("support rule '" + s + "' unknown, expected damp or ignore");
}

std::string toString(ReopenMode m) {
  switch (m) {
    case ReopenMode::kOff: return "off";
    case ReopenMode::kWidth: return "width";
    case ReopenMode::kPrior: return "prior";
    case ReopenMode::kLoad: return "load";
  }
  return "?";
}

ReopenMode reopenModeFromString(const std::string& s) {
  for (auto m : {ReopenMode::kOff, ReopenMode::kWidth, ReopenMode::kPrior, ReopenMode::kLoad}) {
    if (toString(m) == s) return m;
  }
  throw std::invalid_argument("reopen mode '" + s + "' unknown, expected off, width, prior or load");
}

double supportDamping(const Eigen::VectorXd& before, const Eigen::VectorXd& after,
                      const Eigen::VectorXd& lower, const Eigen::VectorXd& upper) {
  double gamma = 1.0;
  for (Eigen::Index i = 0; i < before.size(); ++i) {
    const double step = after[i] - before[i];
    if (!std::isfinite(step)) return 0.0;
    const double margin = std::isfinite(upper[i] - lower[i]) ? 1e-3 * (upper[i] - lower[i]) : 0.0;
    const double lo = lower[i] + margin, hi = upper[i] - margin;
    if (step < 0.0 && std::isfinite(lo) && after[i] < lo) {
      gamma = std::min(gamma, std::max(0.0, (lo - before[i]) / step));
    } else if (step > 0.0 && std::isfinite(hi) && after[i] > hi) {
      gamma = std::min(gamma, std::max(0.0, (hi - before[i]) / step));
    }
  }
  return gamma;
}

void applyDrift(Eigen::MatrixXd& x, int first_parameter, const Eigen::VectorXd& intensity,
                double dt) {
  if (intensity.size() == 0 || !(dt > 0.0) || x.cols() < 2) return;
  const Eigen::Index higher = x.cols() - 1;
  for (Eigen::Index i = 0; i < intensity.size(); ++i) {
    const double q = intensity[i] * intensity[i] * dt;
    const Eigen::Index row = first_parameter + i;
    if (!(q > 0.0) || row >= x.rows()) continue;
    // Directions used by the other rows and this one; a unit vector beyond them.
    Eigen::MatrixXd used(higher, x.rows());
    used.leftCols(row) = x.topRows(row).rightCols(higher).transpose();
    used.col(row) = x.row(row).tail(higher).transpose();
    used.rightCols(x.rows() - row - 1) = x.bottomRows(x.rows() - row - 1).rightCols(higher).transpose();
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(used);
    const Eigen::Index rank = qr.rank();
    if (rank < higher) {
      // Q's column `rank` alone (the reflectors applied to e_rank), not all of Q.
      Eigen::VectorXd direction = Eigen::VectorXd::Unit(higher, rank);
      direction.applyOnTheLeft(qr.householderQ());
      x.row(row).tail(higher) += std::sqrt(q) * direction.transpose();
      continue;
    }
    auto own = x.row(row).tail(higher);
    const double variance = own.squaredNorm();
    if (variance > 0.0) own *= std::sqrt((variance + q) / variance);
  }
}

SettingBreach relinearizeBreach(const RelinearizeSettings& s) {
  if (!(s.shrink >= 0.0 && s.shrink < 1.0)) {
    return {"shrink", std::to_string(s.shrink), "a fraction in [0, 1)"};
  }
  if (!(s.width > 0.0)) return {"width", std::to_string(s.width), "a factor > 0"};
  if (!(s.shrink * s.width < 1.0)) {
    return {"width", std::to_string(s.width),
            "shrink x width < 1 (each restart must narrow the working prior)"};
  }
  return {};
}

void reopenParameters(Eigen::MatrixXd& theta, const Eigen::MatrixXd& prior,
                      const ReopenSettings& s) {
  if (prior.rows() != theta.rows() || prior.cols() != theta.cols()) {
    throw std::invalid_argument("reopenParameters: prior and state differ in size");
  }
  if (s.mode == ReopenMode::kPrior) {
    theta = prior;
  } else if (s.mode == ReopenMode::kWidth) {
    // Widen, never narrow: a parameter the readings barely inform (a vehicle
    // tolerance near its prior's width) keeps its spread and its correlations.
    const Eigen::Index higher = theta.cols() - 1;
    for (Eigen::Index i = 0; i < theta.rows(); ++i) {
      const double wide = s.width * prior.row(i).tail(higher).norm();
      if (theta.row(i).tail(higher).norm() < wide) {
        theta.row(i).tail(higher) = s.width * prior.row(i).tail(higher);
      }
    }
  }
}

namespace {

// The residual `r` (rows of coefficients) moved into the complement of the
// rows of `t`, its Gram matrix r r^T unchanged: r = V S U^T becomes V S U'^T
// with U' the orthonormal basis of that complement nearest to U (polar factor
// of the projected U). Where the complement has no room left (more states
// than free coefficients), the projection itself, which only shrinks r.
Eigen::MatrixXd residualOrthogonalTo(const Eigen::MatrixXd& r, const Eigen::MatrixXd& t) {
  const Eigen::JacobiSVD<Eigen::MatrixXd> rs(r.transpose(), Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::VectorXd sv = rs.singularValues();
  Eigen::Index rank = 0;
  while (rank < sv.size() && sv(rank) > 1e-14 * sv(0)) ++rank;
  if (rank == 0) return Eigen::MatrixXd::Zero(r.rows(), r.cols());
  const Eigen::MatrixXd off_t =
      Eigen::MatrixXd::Identity(t.cols(), t.cols()) -
      t.transpose() * (t * t.transpose()).completeOrthogonalDecomposition().solve(t);
  const Eigen::MatrixXd u = off_t * rs.matrixU().leftCols(rank);
  const Eigen::JacobiSVD<Eigen::MatrixXd> us(u, Eigen::ComputeThinU | Eigen::ComputeThinV);
  if (us.singularValues()(rank - 1) < 1e-12) return (off_t * r.transpose()).transpose();
  const Eigen::MatrixXd u_new = us.matrixU() * us.matrixV().transpose();
  return rs.matrixV().leftCols(rank) * sv.head(rank).asDiagonal() * u_new.transpose();
}

}  // namespace

void reopenExtendedState(Eigen::MatrixXd& x, int first_parameter, const Eigen::MatrixXd& prior,
                         const ReopenSettings& s) {
  const Eigen::Index np = x.rows() - first_parameter, higher = x.cols() - 1;
  Eigen::MatrixXd theta = x.bottomRows(np);
  if (first_parameter == 0 || higher == 0 || s.mode == ReopenMode::kOff) {
    reopenParameters(theta, prior, s);
    x.bottomRows(np) = theta;
    return;
  }
  const Eigen::MatrixXd t_old = theta.rightCols(higher);
  const Eigen::MatrixXd y = x.topRows(first_parameter).rightCols(higher);
  // B^T solves C_tt B^T = C_ty; a rank-deficient C_tt (a parameter without
  // spread) gets the minimum-norm solution.
  const Eigen::MatrixXd c_tt = t_old * t_old.transpose();
  const Eigen::MatrixXd b =
      c_tt.completeOrthogonalDecomposition().solve(t_old * y.transpose()).transpose();
  reopenParameters(theta, prior, s);
  x.bottomRows(np) = theta;
  const Eigen::MatrixXd t_new = theta.rightCols(higher);
  // The states were fitted under the parameters now in doubt: the spread the
  // regression does not explain grows by the parameters' largest factor.
  double grow = 1.0;
  for (Eigen::Index i = 0; i < np; ++i) {
    const double before = t_old.row(i).norm(), after = t_new.row(i).norm();
    if (before > 0.0) grow = std::max(grow, after / before);
  }
  x.topRows(first_parameter).rightCols(higher) =
      b * t_new + grow * residualOrthogonalTo(y - b * t_old, t_new);
}

}  // namespace pc_ekf
