#include "filter/pc_propagator.h"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace pc_ekf {

void ForecastReport::merge(const ForecastReport& o) {
  points = std::max(points, o.points);
  invalid_points += o.invalid_points;
  nonfinite_points += o.nonfinite_points;
  ok = ok && o.ok;
  if (first_problem.empty()) first_problem = o.first_problem;
}

PcPropagator::PcPropagator(std::shared_ptr<const MechanicalModel> model,
                           const PolynomialBasis& basis, const CollocationDesign& design,
                           ParameterMapping mapping, IntegratorSettings settings)
    : model_(std::move(model)),
      basis_(basis),
      design_(design),
      mapping_(std::move(mapping)),
      settings_(settings) {
  if (design_.termCount() != basis_.size()) {
    throw std::invalid_argument("PcPropagator: design and basis sizes differ");
  }
}

Eigen::MatrixXd PcPropagator::priorState() const {
  const int ns = stateCount(), np = parameterCount();
  Eigen::MatrixXd x(ns + np, termCount());
  x.bottomRows(np) = mapping_.priorCoefficients(basis_);
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

ForecastReport PcPropagator::forecast(Eigen::MatrixXd& x, double t0, double t1) const {
  ForecastReport report;
  report.points = design_.pointCount();
  if (t1 < t0) throw std::invalid_argument("forecast: t1 < t0");
  if (t1 == t0) return report;
  const int ns = stateCount(), np = parameterCount();
  std::vector<std::string> reasons;
  const Eigen::MatrixXd params = parametersAtPoints(x.bottomRows(np), &reasons);
  const Eigen::MatrixXd states = design_.evaluateAtPoints(x.topRows(ns));

  std::vector<bool> usable(params.cols(), true);
  std::vector<Eigen::Index> cols;
  for (Eigen::Index q = 0; q < params.cols(); ++q) {
    if (reasons[q].empty() && params.col(q).allFinite() && states.col(q).allFinite()) {
      cols.push_back(q);
      continue;
    }
    usable[q] = false;
    ++report.invalid_points;
    if (report.first_problem.empty()) {
      report.first_problem = "collocation point " + std::to_string(q) + ": " +
                             (reasons[q].empty() ? "non-finite state" : reasons[q]);
    }
  }
  Eigen::MatrixXd valid_params(params.rows(), cols.size());
  Eigen::ArrayXXd y(ns, cols.size());
  for (std::size_t i = 0; i < cols.size(); ++i) {
    valid_params.col(i) = params.col(cols[i]);
    y.col(i) = states.col(cols[i]).array();
  }
  if (!cols.empty()) {
    const auto batch = model_->prepare(valid_params);
    integrate(*model_, *batch, t0, t1, y, settings_);
    integrations_ += static_cast<long>(cols.size());
  }
  Eigen::MatrixXd propagated = Eigen::MatrixXd::Zero(ns, params.cols());
  for (std::size_t i = 0; i < cols.size(); ++i) {
    if (!y.col(i).allFinite()) {
      usable[cols[i]] = false;
      ++report.nonfinite_points;
      if (report.first_problem.empty()) {
        report.first_problem = "collocation point " + std::to_string(cols[i]) +
                               ": integration not finite";
      }
      continue;
    }
    propagated.col(cols[i]) = y.col(i).matrix();
  }
  x.topRows(ns) = project(propagated, usable, &report);
  return report;
}

}  // namespace pc_ekf
