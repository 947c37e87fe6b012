#include "pc_ekf/filter/pc_propagator.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "pc_ekf/filter/small_product.h"

namespace pc_ekf {

void ForecastReport::merge(const ForecastReport& o) {
  points = std::max(points, o.points);
  invalid_points += o.invalid_points;
  nonfinite_points += o.nonfinite_points;
  ok = ok && o.ok;
  if (first_problem.empty()) first_problem = o.first_problem;
  if (loo_error.size() == 0) {
    loo_error = o.loo_error;
  } else if (o.loo_error.size() == loo_error.size()) {
    loo_error = loo_error.cwiseMax(o.loo_error);
  }
}

PcPropagator::PcPropagator(std::shared_ptr<const MechanicalModel> model,
                           const PolynomialBasis& basis, const CollocationDesign& design,
                           ParameterMapping mapping, IntegratorSettings settings, int threads)
    : model_(std::move(model)),
      basis_(basis),
      design_(design),
      mapping_(std::move(mapping)),
      settings_(settings) {
  const int wanted = threads <= 0 ? ColumnWorkers::defaultThreads() : threads;
  if (wanted > 1 && design_.pointCount() >= kBlockedPoints) {
    workers_ = std::make_shared<ColumnWorkers>(wanted);
  }
  if (design_.termCount() != basis_.size()) {
    throw std::invalid_argument("PcPropagator: design and basis sizes differ");
  }
  int modelled = 0;
  while (modelled < model_->observationMatrix().rows() && model_->channelModelled(modelled)) {
    ++modelled;
  }
  loo_observation_ = model_->observationMatrix().topRows(modelled);
}

std::shared_ptr<const PcPropagator> PcPropagator::withThreads(int threads) const {
  return std::make_shared<const PcPropagator>(model_, basis_, design_, mapping_, settings_, threads);
}

Eigen::MatrixXd PcPropagator::priorState() const {
  return stateFor(mapping_.priorCoefficients(basis_));
}

Eigen::MatrixXd PcPropagator::stateFor(const Eigen::MatrixXd& theta) const {
  const int ns = stateCount(), np = parameterCount();
  Eigen::MatrixXd x(ns + np, termCount());
  x.bottomRows(np) = theta;
  std::vector<std::string> reasons;
  const Eigen::MatrixXd params = parametersAtPoints(x.bottomRows(np), &reasons);
  for (const auto& r : reasons) {
    if (!r.empty()) throw std::invalid_argument("prior collocation point invalid: " + r);
  }
  const Eigen::ArrayXXd y0 = model_->prepare(params)->initialState();
  x.topRows(ns) = y0.matrix() * design_.projector().transpose();
  return x;
}

Eigen::MatrixXd PcPropagator::parametersAtPoints(const Eigen::MatrixXd& theta_coeffs,
                                                 std::vector<std::string>* reasons) const {
  const Eigen::MatrixXd full = mapping_.fullParameters(design_.evaluateAtPoints(theta_coeffs));
  if (reasons) {
    reasons->assign(full.cols(), "");
    for (Eigen::Index q = 0; q < full.cols(); ++q) (*reasons)[q] = model_->invalidReason(full.col(q));
  }
  return full;
}

Eigen::MatrixXd PcPropagator::project(const Eigen::MatrixXd& values, const std::vector<bool>& usable,
                                      ForecastReport* report) const {
  Eigen::Index count = 0;
  for (bool u : usable) count += u;
  if (count == static_cast<Eigen::Index>(usable.size())) {
    return values * design_.projector().transpose();
  }
  const int s = termCount();
  Eigen::MatrixXd a(count, s), v(count, values.rows());
  for (Eigen::Index q = 0, r = 0; q < values.cols(); ++q) {
    if (!usable[q]) continue;
    a.row(r) = design_.designMatrix().row(q);
    v.row(r++) = values.col(q).transpose();
  }
  const Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(a);
  if (count < s || cod.rank() < s) {
    report->ok = false;
    if (report->first_problem.empty()) {
      report->first_problem = "only " + std::to_string(count) + " usable collocation points for " +
                              std::to_string(s) + " basis terms";
    }
    return Eigen::MatrixXd::Constant(values.rows(), s, std::numeric_limits<double>::quiet_NaN());
  }
  return cod.solve(v).transpose();
}

}  // namespace pc_ekf
