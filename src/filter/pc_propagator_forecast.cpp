// The forecast (docs/method.md §4.1) in five stages: (1) the states and
// parameters at the collocation points (X A^T), (2) the points'
// admissibility, (3) the integration of the points' models over [t0, t1],
// (4) the projection back onto the basis and (5) the leave-one-out error of
// the channels. Two algorithms run them:
//   forecastInBlocks (pc_propagator_in_blocks.cpp), for designs of
//     kBlockedPoints or more: threads take parts made of whole blocks of
//     kBlock points and do every per-point stage of their part; a block's
//     sums run over its points in order and the blocks are added in block
//     order, so no sum depends on the split among threads. An unusable point
//     makes it give up;
//   forecastDroppingUnusable (pc_propagator_dropping_unusable.cpp), for
//     small designs and when forecastInBlocks gives up: the points are
//     evaluated at once, the usable ones integrated in parts on the threads,
//     and one sum over all points projects them; unusable points are dropped
//     (least squares on the rest).
// This file: the choice between them and the stages they share.
#include "pc_ekf/filter/pc_propagator_forecast.h"

#include <stdexcept>

#include "pc_ekf/filter/small_product.h"

namespace pc_ekf {

void PcPropagator::runParts(const std::vector<long>& bounds,
                            const std::function<void(int, long, long)>& job) const {
  if (workers_) {
    workers_->run(bounds, job);
    return;
  }
  for (std::size_t i = 0; i + 1 < bounds.size(); ++i)
    job(static_cast<int>(i), bounds[i], bounds[i + 1]);
}

ForecastReport PcPropagator::forecast(Eigen::MatrixXd& x, double t0, double t1) const {
  ForecastReport report;
  report.points = design_.pointCount();
  if (t1 < t0) throw std::invalid_argument("forecast: t1 < t0");
  if (t1 == t0) return report;
  thread_local ForecastWork work;
  work.at_points.resize(x.rows(), design_.pointCount());
  work.params.resize(model_->nominalParameters().size(), design_.pointCount());
  if (design_.pointCount() < kBlockedPoints || !forecastInBlocks(x, t0, t1, work, &report)) {
    forecastDroppingUnusable(x, t0, t1, work, &report);
  }
  return report;
}

// (A^T)(l, q) = A[q + l Q]; the full parameters from the mapping.
void PcPropagator::evaluatePoints(const Eigen::MatrixXd& x, Eigen::Index begin, Eigen::Index end,
                                  ForecastWork& work) const {
  smallProduct(x.data(), design_.designMatrix().data() + begin, design_.pointCount(), 1,
               &work.at_points(0, begin), x.rows(), x.cols(), end - begin);
  mapping_.fillFullParameters(work.at_points.bottomRows(parameterCount()), begin, end,
                              work.params);
}

// Each column is independent of the others of its batch.
void PcPropagator::integratePoints(const Eigen::MatrixXd& params, Eigen::ArrayXXd& y, double t0,
                                   double t1) const {
  const auto batch = model_->prepare(params);
  integrate(*model_, *batch, t0, t1, y, settings_);
}

// (P^T)(q, j) = P[j + q S].
void PcPropagator::projectBlock(Eigen::Index b, Eigen::Index q0, Eigen::Index nq,
                                const double* y_cols, ForecastWork& work) const {
  const Eigen::Index s_count = termCount();
  const int ns = stateCount();
  smallProduct(y_cols, design_.projector().data() + q0 * s_count, s_count, 1,
               work.state_sums.data() + b * s_count * ns, ns, nq, s_count);
}

}  // namespace pc_ekf
