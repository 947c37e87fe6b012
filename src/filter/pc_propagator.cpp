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
  for (const UncertainParameter& u : mapping_.uncertain()) {
    full_index_.push_back(model_->parameterIndex(u.name));  // valid: checked by the mapping
  }
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

namespace {

// Per-thread buffers of forecast(): the per-sample path allocates nothing once
// they have their size (the propagator is shared, e.g. by the node's filters).
struct ForecastWork {
  Eigen::MatrixXd at_points;  // (states + parameters) x Q
  Eigen::MatrixXd params;     // model parameters x Q
  Eigen::ArrayXXd y;          // states x (usable points)
  std::vector<std::string> reasons;
  std::vector<bool> usable;
  std::vector<Eigen::Index> cols;
};

}  // namespace

ForecastReport PcPropagator::forecast(Eigen::MatrixXd& x, double t0, double t1) const {
  ForecastReport report;
  report.points = design_.pointCount();
  if (t1 < t0) throw std::invalid_argument("forecast: t1 < t0");
  if (t1 == t0) return report;
  if (design_.pointCount() >= kBlockedPoints && forecastInBlocks(x, t0, t1, &report)) return report;
  const int ns = stateCount(), np = parameterCount();
  const Eigen::Index q_count = design_.pointCount();
  thread_local ForecastWork w;
  // States and parameters at the points in one product: X A^T.
  // X A^T: A is Q x S column-major, so (A^T)(l, q) = A[q + l Q].
  const Eigen::MatrixXd& design = design_.designMatrix();
  w.at_points.resize(x.rows(), q_count);
  smallProduct(x.data(), design.data(), q_count, 1, w.at_points.data(), x.rows(), x.cols(),
               q_count);
  // Full model parameters at the points: nominal values, uncertain rows replaced.
  // (Column copies: Eigen's replicate() divides per element.)
  const Eigen::VectorXd& nominal = model_->nominalParameters();
  w.params.resize(nominal.size(), q_count);
  for (Eigen::Index q = 0; q < q_count; ++q) w.params.col(q) = nominal;
  for (int i = 0; i < np; ++i) w.params.row(full_index_[i]) = w.at_points.row(ns + i);
  const Eigen::MatrixXd& params = w.params;
  w.reasons.resize(q_count);
  w.usable.assign(q_count, true);
  w.cols.clear();
  const bool all_finite = allFiniteFast(params) && allFiniteFast(w.at_points.topRows(ns));
  for (Eigen::Index q = 0; q < q_count; ++q) {
    w.reasons[q] = model_->invalidReason(params.col(q));
    if (w.reasons[q].empty() &&
        (all_finite || (params.col(q).allFinite() && w.at_points.col(q).head(ns).allFinite()))) {
      w.cols.push_back(q);
      continue;
    }
    w.usable[q] = false;
    ++report.invalid_points;
    if (report.first_problem.empty()) {
      report.first_problem = "collocation point " + std::to_string(q) + ": " +
                             (w.reasons[q].empty() ? "non-finite state" : w.reasons[q]);
    }
  }
  const Eigen::Index valid = static_cast<Eigen::Index>(w.cols.size());
  w.y.resize(ns, valid);
  if (valid == q_count) {
    w.y = w.at_points.topRows(ns).array();
  } else {
    for (Eigen::Index i = 0; i < valid; ++i) w.y.col(i) = w.at_points.col(w.cols[i]).head(ns).array();
  }
  const std::vector<long> parts =
      workers_ ? columnParts(valid, 2 * workers_->threads(), kMinPointsPerPart)
               : std::vector<long>{};
  if (valid > 0 && parts.size() > 2) {
    // Each part prepares and integrates its own columns (boundaries at SIMD
    // multiples, so every column takes the same code path as in one batch).
    ForecastWork& work = w;  // the caller's buffers (w names each thread's own)
    workers_->run(parts, [&](int, long begin, long end) {
      thread_local Eigen::ArrayXXd y_part;
      const Eigen::Index count = end - begin;
      const std::vector<Eigen::Index> cols(work.cols.begin() + begin, work.cols.begin() + end);
      const auto batch = model_->prepare(params(Eigen::all, cols));
      y_part = work.y.middleCols(begin, count);
      integrate(*model_, *batch, t0, t1, y_part, settings_);
      work.y.middleCols(begin, count) = y_part;
    });
    integrations_ += static_cast<long>(valid);
  } else if (valid > 0) {
    const auto batch = valid == q_count ? model_->prepare(params)
                                        : model_->prepare(params(Eigen::all, w.cols));
    integrate(*model_, *batch, t0, t1, w.y, settings_);
    integrations_ += static_cast<long>(valid);
  }
  const bool integrated_finite = allFiniteFast(w.y);
  for (Eigen::Index i = 0; i < valid && !integrated_finite; ++i) {
    if (w.y.col(i).allFinite()) continue;
    w.usable[w.cols[i]] = false;
    ++report.nonfinite_points;
    if (report.first_problem.empty()) {
      report.first_problem =
          "collocation point " + std::to_string(w.cols[i]) + ": integration not finite";
    }
  }
  if (report.invalid_points == 0 && report.nonfinite_points == 0) {
    // Every point usable: the precomputed projector.
    // Y P^T: P is S x Q column-major, so (P^T)(q, j) = P[j + q S].
    const Eigen::MatrixXd& projector = design_.projector();
    const Eigen::Index s_count = projector.rows();
    w.at_points.resize(ns, s_count);
    smallProduct(w.y.data(), projector.data(), s_count, 1, w.at_points.data(), ns, q_count,
                 s_count);
    x.topRows(ns) = w.at_points;
    if (design_.hasLeaveOneOut()) {
      report.loo_error = design_.leaveOneOutError(model_->observationMatrix() * w.y.matrix());
    }
    return report;
  }
  Eigen::MatrixXd propagated = Eigen::MatrixXd::Zero(ns, q_count);
  for (Eigen::Index i = 0; i < valid; ++i) {
    if (w.usable[w.cols[i]]) propagated.col(w.cols[i]) = w.y.col(i).matrix();
  }
  x.topRows(ns) = project(propagated, w.usable, &report);
  return report;
}

}  // namespace pc_ekf
