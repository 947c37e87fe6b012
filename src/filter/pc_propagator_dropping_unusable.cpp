// The forecast that drops unusable points (pc_propagator_forecast.cpp): the
// points evaluated at once, the usable ones integrated in parts on the
// threads, one sum over all points projecting them, least squares on the
// usable ones when some were dropped. It takes every design under
// kBlockedPoints and every sample forecastInBlocks gives up on.
#include <string>

#include "pc_ekf/filter/pc_propagator_forecast.h"
#include "pc_ekf/filter/small_product.h"

namespace pc_ekf {

namespace {

// Stage 2: the points whose parameters are in the model's domain and whose
// states and parameters are finite (work.cols, their start states in
// work.y); the others counted and marked unusable. Returns their count.
Eigen::Index keepUsablePoints(const MechanicalModel& model, int ns, ForecastWork& work,
                              ForecastReport* report) {
  const Eigen::MatrixXd& params = work.params;
  const Eigen::Index q_count = params.cols();
  work.reasons.resize(q_count);
  work.usable.assign(q_count, true);
  work.cols.clear();
  const bool all_finite = allFiniteFast(params) && allFiniteFast(work.at_points.topRows(ns));
  for (Eigen::Index q = 0; q < q_count; ++q) {
    work.reasons[q] = model.invalidReason(params.col(q));
    if (work.reasons[q].empty() &&
        (all_finite || (params.col(q).allFinite() && work.at_points.col(q).head(ns).allFinite()))) {
      work.cols.push_back(q);
      continue;
    }
    work.usable[q] = false;
    ++report->invalid_points;
    if (report->first_problem.empty()) {
      report->first_problem = "collocation point " + std::to_string(q) + ": " +
                              (work.reasons[q].empty() ? "non-finite state" : work.reasons[q]);
    }
  }
  const Eigen::Index valid = static_cast<Eigen::Index>(work.cols.size());
  work.y.resize(ns, valid);
  if (valid == q_count) {
    work.y = work.at_points.topRows(ns).array();
  } else {
    for (Eigen::Index i = 0; i < valid; ++i)
      work.y.col(i) = work.at_points.col(work.cols[i]).head(ns).array();
  }
  return valid;
}

// After stage 3: the kept points whose integration is not finite are counted
// and marked unusable.
void dropNonFinitePoints(ForecastWork& work, ForecastReport* report) {
  const Eigen::Index valid = static_cast<Eigen::Index>(work.cols.size());
  const bool integrated_finite = allFiniteFast(work.y);
  for (Eigen::Index i = 0; i < valid && !integrated_finite; ++i) {
    if (work.y.col(i).allFinite()) continue;
    work.usable[work.cols[i]] = false;
    ++report->nonfinite_points;
    if (report->first_problem.empty()) {
      report->first_problem =
          "collocation point " + std::to_string(work.cols[i]) + ": integration not finite";
    }
  }
}

}  // namespace

void PcPropagator::forecastDroppingUnusable(Eigen::MatrixXd& x, double t0, double t1,
                                            ForecastWork& work, ForecastReport* report) const {
  const int ns = stateCount();
  const Eigen::Index q_count = design_.pointCount(), s_count = termCount();
  evaluatePoints(x, 0, q_count, work);  // stage 1, every point at once
  const Eigen::Index valid = keepUsablePoints(*model_, ns, work, report);
  const Eigen::MatrixXd& params = work.params;

  // Stage 3: parts of the usable points (boundaries at SIMD multiples, so
  // every column takes the same code path as in one batch).
  const std::vector<long> parts =
      workers_ ? columnParts(valid, 2 * workers_->threads(), kMinPointsPerPart)
               : std::vector<long>{};
  if (valid > 0 && parts.size() > 2) {
    workers_->run(parts, [&](int, long begin, long end) {
      thread_local Eigen::ArrayXXd y_part;
      const Eigen::Index count = end - begin;
      const std::vector<Eigen::Index> cols(work.cols.begin() + begin, work.cols.begin() + end);
      y_part = work.y.middleCols(begin, count);
      integratePoints(params(Eigen::all, cols), y_part, t0, t1);
      work.y.middleCols(begin, count) = y_part;
    });
    integrations_ += static_cast<long>(valid);
  } else if (valid > 0) {
    if (valid == q_count) {
      integratePoints(params, work.y, t0, t1);
    } else {
      integratePoints(params(Eigen::all, work.cols), work.y, t0, t1);
    }
    integrations_ += static_cast<long>(valid);
  }
  dropNonFinitePoints(work, report);

  if (report->invalid_points == 0 && report->nonfinite_points == 0) {
    // Stage 4, every point usable: one block of all points (the
    // precomputed projector); stage 5 the design's leave-one-out error.
    work.state_sums.resize(ns, s_count);
    projectBlock(0, 0, q_count, work.y.data(), work);
    x.topRows(ns) = blockSums(work.state_sums, ns, s_count, 0);
    if (design_.hasLeaveOneOut()) {
      report->loo_error = design_.leaveOneOutError(loo_observation_ * work.y.matrix());
    }
    return;
  }
  // Stage 4 without the unusable points: least squares on the rest.
  Eigen::MatrixXd propagated = Eigen::MatrixXd::Zero(ns, q_count);
  for (Eigen::Index i = 0; i < valid; ++i) {
    if (work.usable[work.cols[i]]) propagated.col(work.cols[i]) = work.y.col(i).matrix();
  }
  x.topRows(ns) = project(propagated, work.usable, report);
}

}  // namespace pc_ekf
