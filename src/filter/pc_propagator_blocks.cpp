// The blocked forecast of large designs. Threads take parts made of whole
// blocks; a block's sums run over its points in order and the blocks are
// added in block order, so no sum depends on the split among threads.
#include <algorithm>
#include <cmath>

#include "pc_ekf/filter/pc_propagator.h"
#include "pc_ekf/filter/small_product.h"

namespace pc_ekf {

namespace {

// Per-thread buffers (the caller's; the parts write disjoint columns).
struct BlockWork {
  Eigen::MatrixXd at_points;     // (states + parameters) x Q
  Eigen::MatrixXd params;        // model parameters x Q
  Eigen::ArrayXXd y;             // states x Q, integrated
  Eigen::MatrixXd z;             // channels x Q: H y
  Eigen::MatrixXd state_sums;    // states x (S blocks): Y_b P_b^T of block b
  Eigen::MatrixXd channel_sums;  // channels x (S blocks): Z_b pinv(A)_b^T (quadrature)
  // channels x blocks: sum z, sum z^2, sum of squared leave-one-out errors,
  // sum (z - mean)^2.
  Eigen::MatrixXd sum, sum_sq, err_sq, spread;
  Eigen::MatrixXd coeffs;  // channels x S: the least-squares fit of z
  Eigen::ArrayXd mean;
  std::vector<char> unusable;  // per part
  std::vector<long> bounds;
};

// Sum of the blocks' columns (rows x blocks), in block order.
Eigen::VectorXd sumOfBlocks(const Eigen::MatrixXd& per_block) {
  Eigen::VectorXd total = per_block.col(0);
  for (Eigen::Index b = 1; b < per_block.cols(); ++b) total += per_block.col(b);
  return total;
}

}  // namespace

void PcPropagator::runParts(const std::vector<long>& bounds,
                            const std::function<void(int, long, long)>& job) const {
  if (workers_) {
    workers_->run(bounds, job);
    return;
  }
  for (std::size_t i = 0; i + 1 < bounds.size(); ++i)
    job(static_cast<int>(i), bounds[i], bounds[i + 1]);
}

bool PcPropagator::forecastInBlocks(Eigen::MatrixXd& x, double t0, double t1,
                                    ForecastReport* report) const {
  const int ns = stateCount(), np = parameterCount();
  const Eigen::Index q_count = design_.pointCount(), s_count = termCount();
  const Eigen::Index blocks = (q_count + kBlock - 1) / kBlock;
  const Eigen::MatrixXd& design = design_.designMatrix();
  const Eigen::MatrixXd& projector = design_.projector();
  const Eigen::MatrixXd& pinv = design_.leastSquaresProjector();
  const Eigen::VectorXd& loo_scale = design_.leaveOneOutScale();
  const Eigen::MatrixXd& h = model_->observationMatrix();
  const bool loo = design_.hasLeaveOneOut();
  // The projector is the pseudo-inverse: the channels' fit is H times the
  // states' coefficients, no second sum over the points.
  const bool regression = &pinv == &projector;
  const Eigen::Index nz = loo ? h.rows() : 0;
  const Eigen::VectorXd& nominal = model_->nominalParameters();

  thread_local BlockWork w;
  BlockWork& work = w;  // the caller's buffers (w names each thread's own)
  w.at_points.resize(x.rows(), q_count);
  w.params.resize(nominal.size(), q_count);
  w.y.resize(ns, q_count);
  w.state_sums.resize(ns, s_count * blocks);
  w.z.resize(nz, q_count);
  w.channel_sums.resize(nz, regression ? 0 : s_count * blocks);
  for (Eigen::MatrixXd* m : {&w.sum, &w.sum_sq, &w.err_sq, &w.spread}) m->resize(nz, blocks);
  // Parts of whole blocks, one per thread (each part repeats the integrator's
  // per-step work, so more parts cost more than they balance), taken by
  // whichever thread is free.
  const std::vector<long> block_bounds =
      columnParts(blocks, workers_ ? workers_->threads() : 1, 1, 1);
  w.bounds.clear();
  for (long b : block_bounds) w.bounds.push_back(std::min<long>(b * kBlock, q_count));
  w.unusable.assign(w.bounds.size() - 1, 0);

  runParts(w.bounds, [&](int part, long begin, long end) {
    const Eigen::Index count = end - begin;
    // States and parameters at the part's points: X A^T, (A^T)(l, q) = A[q + l Q].
    smallProduct(x.data(), design.data() + begin, q_count, 1, &work.at_points(0, begin), x.rows(),
                 x.cols(), count);
    for (Eigen::Index q = begin; q < end; ++q) {
      work.params.col(q) = nominal;
      for (int i = 0; i < np; ++i) work.params(full_index_[i], q) = work.at_points(ns + i, q);
    }
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
    const auto batch = model_->prepare(part_params);
    y_part = work.at_points.block(0, begin, ns, count).array();
    integrate(*model_, *batch, t0, t1, y_part, settings_);
    if (!allFiniteFast(y_part)) {
      work.unusable[part] = 1;
      return;
    }
    work.y.middleCols(begin, count) = y_part;
    for (Eigen::Index b = begin / kBlock; b * kBlock < end; ++b) {
      const Eigen::Index q0 = b * kBlock, nq = std::min<Eigen::Index>(kBlock, q_count - q0);
      // Y_b P_b^T, (P^T)(q, j) = P[j + q S].
      smallProduct(&work.y(0, q0), projector.data() + q0 * s_count, s_count, 1,
                   work.state_sums.data() + b * s_count * ns, ns, nq, s_count);
      if (!loo) continue;
      smallProduct(h.data(), &work.y(0, q0), 1, ns, &work.z(0, q0), nz, ns, nq);
      if (!regression) {
        smallProduct(&work.z(0, q0), pinv.data() + q0 * s_count, s_count, 1,
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
  });
  if (std::any_of(w.unusable.begin(), w.unusable.end(), [](char u) { return u != 0; })) {
    return false;
  }
  integrations_ += static_cast<long>(q_count);
  auto block = [&](const Eigen::MatrixXd& sums, Eigen::Index rows, Eigen::Index b) {
    return Eigen::Map<const Eigen::MatrixXd>(sums.data() + b * s_count * rows, rows, s_count);
  };
  x.topRows(ns) = block(w.state_sums, ns, 0);
  for (Eigen::Index b = 1; b < blocks; ++b) x.topRows(ns) += block(w.state_sums, ns, b);
  if (!loo) return true;

  // Leave-one-out error from the fit of z (as CollocationDesign::leaveOneOutError).
  if (regression) {
    w.coeffs.resize(nz, s_count);
    smallProduct(h.data(), x.data(), 1, x.rows(), w.coeffs.data(), nz, ns, s_count);
  } else {
    w.coeffs = block(w.channel_sums, nz, 0);
    for (Eigen::Index b = 1; b < blocks; ++b) w.coeffs += block(w.channel_sums, nz, b);
  }
  w.mean = sumOfBlocks(w.sum).array() / static_cast<double>(q_count);
  runParts(w.bounds, [&](int, long begin, long end) {
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
  const Eigen::VectorXd err_sq = sumOfBlocks(w.err_sq), spread = sumOfBlocks(w.spread),
                        sum_sq = sumOfBlocks(w.sum_sq);
  report->loo_error.resize(nz);
  for (Eigen::Index i = 0; i < nz; ++i) {
    // Values equal at every point fit exactly: no error, whatever rounding leaves.
    report->loo_error(i) = spread(i) > 1e-24 * sum_sq(i) ? std::sqrt(err_sq(i) / spread(i)) : 0.0;
  }
  return true;
}

}  // namespace pc_ekf
