#include "filter/update_safeguards.h"

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
  }
  return "?";
}

ReopenMode reopenModeFromString(const std::string& s) {
  for (auto m : {ReopenMode::kOff, ReopenMode::kWidth, ReopenMode::kPrior}) {
    if (toString(m) == s) return m;
  }
  throw std::invalid_argument("reopen mode '" + s + "' unknown, expected off, width or prior");
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

void applyDrift(Eigen::MatrixXd& theta, const Eigen::VectorXd& intensity, double dt,
                const PolynomialBasis& basis) {
  if (intensity.size() == 0 || !(dt > 0.0)) return;
  for (Eigen::Index i = 0; i < theta.rows() && i < intensity.size(); ++i) {
    const double q = intensity[i] * intensity[i] * dt;
    if (!(q > 0.0)) continue;
    auto higher = theta.row(i).tail(theta.cols() - 1);
    const double variance = higher.squaredNorm();
    if (variance > 0.0) {
      higher *= std::sqrt((variance + q) / variance);
      continue;
    }
    const auto& indices = basis.multiIndices();
    for (std::size_t j = 1; j < indices.size(); ++j) {
      int total = 0;
      for (int e : indices[j]) total += e;
      if (total == 1 && indices[j][static_cast<std::size_t>(i)] == 1) {
        theta(i, static_cast<Eigen::Index>(j)) = std::sqrt(q);
        break;
      }
    }
  }
}

void reopenParameters(Eigen::MatrixXd& theta, const Eigen::MatrixXd& prior,
                      const ReopenSettings& s) {
  if (prior.rows() != theta.rows() || prior.cols() != theta.cols()) {
    throw std::invalid_argument("reopenParameters: prior and state differ in size");
  }
  if (s.mode == ReopenMode::kPrior) {
    theta = prior;
  } else if (s.mode == ReopenMode::kWidth) {
    theta.rightCols(theta.cols() - 1) = s.width * prior.rightCols(prior.cols() - 1);
  }
}

}  // namespace pc_ekf
