// The forecast in fixed blocks (pc_propagator_forecast.cpp): threads take
// parts made of whole blocks of kBlock points and do every per-point stage
// of their part; a block's sums run over its points in order and the blocks
// are added in block order, so that the result is bitwise the same on any
// thread count. An unusable point makes it give up (the caller then drops
// the point with forecastDroppingUnusable).
#include <algorithm>
#include <cmath>

#include "pc_ekf/filter/pc_propagator_forecast.h"
#include "pc_ekf/filter/small_product.h"

namespace pc_ekf {

namespace {

// Sum of the blocks' columns (rows x blocks), in block order.
Eigen::VectorXd sumOfBlocks(const Eigen::MatrixXd& per_block) {
  Eigen::VectorXd total = per_block.col(0);
  for (Eigen::Index b = 1; b < per_block.cols(); ++b) total += per_block.col(b);
  return total;
}

// The projector is the pseudo-inverse: the channels' fit is H times the
// states' coefficients, no second sum over the points.
bool fitByRegression(const CollocationDesign& design) {
  return &design.leastSquaresProjector() == &design.projector();
}

}  // namespace

bool PcPropagator::forecastInBlocks(Eigen::MatrixXd& x, double t0, double t1, ForecastWork& work,
                                    ForecastReport* report) const {
  const int ns = stateCount();
  const Eigen::Index q_count = design_.pointCount(), s_count = termCount();
  const Eigen::Index blocks = (q_count + kBlock - 1) / kBlock;
  const bool loo = design_.hasLeaveOneOut();
  const Eigen::Index nz = loo ? loo_observation_.rows() : 0;
  work.y.resize(ns, q_count);
  work.state_sums.resize(ns, s_count * blocks);
  work.z.resize(nz, q_count);
  work.channel_sums.resize(nz, fitByRegression(design_) ? 0 : s_count * blocks);
  for (Eigen::MatrixXd* m : {&work.sum, &work.sum_sq, &work.err_sq, &work.spread}) {
    m->resize(nz, blocks);
  }
  // Parts of whole blocks, one per thread (each part repeats the integrator's
  // per-step work, so more parts cost more than they balance), taken by
  // whichever thread is free.
  const std::vector<long> block_bounds =
      columnParts(blocks, workers_ ? workers_->threads() : 1, 1, 1);
  work.bounds.clear();
  for (long b : block_bounds) work.bounds.push_back(std::min<long>(b * kBlock, q_count));
  work.unusable.assign(work.bounds.size() - 1, 0);

  runParts(work.bounds, [&](int part, long begin, long end) {
    const Eigen::Index count = end - begin;
    evaluatePoints(x, begin, end, work);  // stage 1
    // Stage 2: any unusable point, and forecastDroppingUnusable takes over.
    if (!allFiniteFast(work.params.middleCols(begin, count)) ||
        !allFiniteFast(work.at_points.block(0, begin, ns, count))) {
      work.unusable[part] = 1;
      return;
    }
    for (Eigen::Index q = begin; q < end; ++q) {
      if (!model_->invalidReason(work.params.col(q)).empty()) {
        work.unusable[part] = 1;
        return;
      }
    }
    thread_local Eigen::MatrixXd part_params;
    thread_local Eigen::ArrayXXd y_part;
    part_params = work.params.middleCols(begin, count);
    y_part = work.at_points.block(0, begin, ns, count).array();
    integratePoints(part_params, y_part, t0, t1);  // stage 3
    if (!allFiniteFast(y_part)) {
      work.unusable[part] = 1;
      return;
    }
    work.y.middleCols(begin, count) = y_part;
    for (Eigen::Index b = begin / kBlock; b * kBlock < end; ++b) sumBlock(b, work);
  });
  if (std::any_of(work.unusable.begin(), work.unusable.end(), [](char u) { return u != 0; })) {
    return false;
  }
  integrations_ += static_cast<long>(q_count);
  x.topRows(ns) = blockSums(work.state_sums, ns, s_count, 0);
  for (Eigen::Index b = 1; b < blocks; ++b) {
    x.topRows(ns) += blockSums(work.state_sums, ns, s_count, b);
  }
  if (loo) leaveOneOutInBlocks(x, work, report);
  return true;
}

// Stage 4's share of block b, and the channels' sums over its points that
// stage 5 needs (z = H y, its fit's share and its first two moments).
void PcPropagator::sumBlock(Eigen::Index b, ForecastWork& work) const {
  const int ns = stateCount();
  const Eigen::Index q_count = design_.pointCount(), s_count = termCount();
  const Eigen::Index q0 = b * kBlock, nq = std::min<Eigen::Index>(kBlock, q_count - q0);
  projectBlock(b, q0, nq, &work.y(0, q0), work);
  if (!design_.hasLeaveOneOut()) return;
  const Eigen::MatrixXd& h = loo_observation_;
  const Eigen::Index nz = h.rows();
  smallProduct(h.data(), &work.y(0, q0), 1, ns, &work.z(0, q0), nz, ns, nq);
  if (!fitByRegression(design_)) {
    smallProduct(&work.z(0, q0), design_.leastSquaresProjector().data() + q0 * s_count, s_count, 1,
                 work.channel_sums.data() + b * s_count * nz, nz, nq, s_count);
  }
  for (Eigen::Index i = 0; i < nz; ++i) {
    double sum = 0.0, sum_sq = 0.0;
    for (Eigen::Index q = q0; q < q0 + nq; ++q) {
      sum += work.z(i, q);
      sum_sq += work.z(i, q) * work.z(i, q);
    }
    work.sum(i, b) = sum;
    work.sum_sq(i, b) = sum_sq;
  }
}

// Stage 5: the leave-one-out error from the fit of z (as
// CollocationDesign::leaveOneOutError), per block.
void PcPropagator::leaveOneOutInBlocks(const Eigen::MatrixXd& x, ForecastWork& work,
                                       ForecastReport* report) const {
  const int ns = stateCount();
  const Eigen::Index q_count = design_.pointCount(), s_count = termCount();
  const Eigen::Index blocks = (q_count + kBlock - 1) / kBlock;
  const Eigen::MatrixXd& h = loo_observation_;
  const Eigen::Index nz = h.rows();
  const Eigen::MatrixXd& design = design_.designMatrix();
  const Eigen::VectorXd& loo_scale = design_.leaveOneOutScale();
  if (fitByRegression(design_)) {
    work.coeffs.resize(nz, s_count);
    smallProduct(h.data(), x.data(), 1, x.rows(), work.coeffs.data(), nz, ns, s_count);
  } else {
    work.coeffs = blockSums(work.channel_sums, nz, s_count, 0);
    for (Eigen::Index b = 1; b < blocks; ++b) {
      work.coeffs += blockSums(work.channel_sums, nz, s_count, b);
    }
  }
  work.mean = sumOfBlocks(work.sum).array() / static_cast<double>(q_count);
  runParts(work.bounds, [&](int, long begin, long end) {
    thread_local Eigen::MatrixXd fitted;
    for (Eigen::Index b = begin / kBlock; b * kBlock < end; ++b) {
      const Eigen::Index q0 = b * kBlock, nq = std::min<Eigen::Index>(kBlock, q_count - q0);
      fitted.resize(nz, nq);
      smallProduct(work.coeffs.data(), design.data() + q0, q_count, 1, fitted.data(), nz, s_count,
                   nq);
      for (Eigen::Index i = 0; i < nz; ++i) {
        double err_sq = 0.0, spread = 0.0;
        for (Eigen::Index j = 0; j < nq; ++j) {
          const double e = (work.z(i, q0 + j) - fitted(i, j)) * loo_scale(q0 + j);
          const double d = work.z(i, q0 + j) - work.mean(i);
          err_sq += e * e;
          spread += d * d;
        }
        work.err_sq(i, b) = err_sq;
        work.spread(i, b) = spread;
      }
    }
  });
  const Eigen::VectorXd err_sq = sumOfBlocks(work.err_sq), spread = sumOfBlocks(work.spread),
                        sum_sq = sumOfBlocks(work.sum_sq);
  report->loo_error.resize(nz);
  for (Eigen::Index i = 0; i < nz; ++i) {
    // Values equal at every point fit exactly: no error, whatever rounding leaves.
    report->loo_error(i) = spread(i) > 1e-24 * sum_sq(i) ? std::sqrt(err_sq(i) / spread(i)) : 0.0;
  }
}

}  // namespace pc_ekf
