// The forecast pipeline (docs/method.md §4.1): the states and parameters at
// the collocation points (X A^T), the points' admissibility, the
// integration of the points' models over [t0, t1], the projection back onto
// the basis and the leave-one-out error of the channels. One pipeline, two
// ways of splitting its work (PcPropagator::ForecastSplit):
//   kUnsplit: the points are evaluated at once, the usable ones integrated
//     in parts on the threads, and one sum over all points projects them;
//     unusable points are dropped (least squares on the rest);
//   kBlocked: threads take parts made of whole blocks of kBlock points and
//     do every per-point step of their part; a block's sums run over its
//     points in order and the blocks are added in block order, so no sum
//     depends on the split among threads; an unusable point makes it give up
//     (the caller then takes kUnsplit).
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "pc_ekf/filter/pc_propagator.h"
#include "pc_ekf/filter/small_product.h"

namespace pc_ekf {

namespace {

// Per-thread buffers (the caller's; parts write disjoint columns): the
// per-sample path allocates nothing once they have their size (the
// propagator is shared, e.g. by the node's filters).
struct ForecastWork {
  Eigen::MatrixXd at_points;  // (states + parameters) x Q
  Eigen::MatrixXd params;     // model parameters x Q
  Eigen::ArrayXXd y;          // states x (usable points), integrated
  std::vector<std::string> reasons;
  std::vector<bool> usable;
  std::vector<Eigen::Index> cols;  // kUnsplit: the usable points
  Eigen::MatrixXd z;               // channels x Q: H y
  Eigen::MatrixXd state_sums;      // states x (S blocks): Y_b P_b^T of block b
  Eigen::MatrixXd channel_sums;    // channels x (S blocks): Z_b pinv(A)_b^T (quadrature)
  // channels x blocks: sum z, sum z^2, sum of squared leave-one-out errors,
  // sum (z - mean)^2.
  Eigen::MatrixXd sum, sum_sq, err_sq, spread;
  Eigen::MatrixXd coeffs;  // channels x S: the least-squares fit of z
  Eigen::ArrayXd mean;
  std::vector<char> unusable;  // kBlocked: per part
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

ForecastReport PcPropagator::forecast(Eigen::MatrixXd& x, double t0, double t1) const {
  ForecastReport report;
  report.points = design_.pointCount();
  if (t1 < t0) throw std::invalid_argument("forecast: t1 < t0");
  if (t1 == t0) return report;
  if (design_.pointCount() < kBlockedPoints ||
      !forecastWith(ForecastSplit::kBlocked, x, t0, t1, &report)) {
    forecastWith(ForecastSplit::kUnsplit, x, t0, t1, &report);
  }
  return report;
}

bool PcPropagator::forecastWith(ForecastSplit split, Eigen::MatrixXd& x, double t0, double t1,
                                ForecastReport* report) const {
  const bool blocked = split == ForecastSplit::kBlocked;
  const int ns = stateCount(), np = parameterCount();
  const Eigen::Index q_count = design_.pointCount(), s_count = termCount();
  const Eigen::MatrixXd& design = design_.designMatrix();
  const Eigen::MatrixXd& projector = design_.projector();
  const Eigen::VectorXd& nominal = model_->nominalParameters();
  thread_local ForecastWork w;
  ForecastWork& work = w;  // the caller's buffers (w names each thread's own)

  // Stage 1 for points [begin, end): X A^T, (A^T)(l, q) = A[q + l Q], and the
  // full model parameters (nominal values, the uncertain rows replaced).
  const auto evaluatePoints = [&](Eigen::Index begin, Eigen::Index end) {
    smallProduct(x.data(), design.data() + begin, q_count, 1, &work.at_points(0, begin), x.rows(),
                 x.cols(), end - begin);
    for (Eigen::Index q = begin; q < end; ++q) {
      work.params.col(q) = nominal;  // column copies: Eigen's replicate() divides per element
      for (int i = 0; i < np; ++i) work.params(full_index_[i], q) = work.at_points(ns + i, q);
    }
  };
  // Stage 3: the points' models from t0 to t1 (each column independent of
  // the others of its batch).
  const auto integratePoints = [&](const Eigen::MatrixXd& params, Eigen::ArrayXXd& y) {
    const auto batch = model_->prepare(params);
    integrate(*model_, *batch, t0, t1, y, settings_);
  };
  // Stage 4 for the points [q0, q0 + nq) of `y` (their columns from y_col):
  // block b's Y_b P_b^T, (P^T)(q, j) = P[j + q S].
  const auto projectBlock = [&](Eigen::Index b, Eigen::Index q0, Eigen::Index nq,
                                const double* y_cols) {
    smallProduct(y_cols, projector.data() + q0 * s_count, s_count, 1,
                 work.state_sums.data() + b * s_count * ns, ns, nq, s_count);
  };
  const auto sumBlocks = [&](const Eigen::MatrixXd& sums, Eigen::Index rows, Eigen::Index b) {
    return Eigen::Map<const Eigen::MatrixXd>(sums.data() + b * s_count * rows, rows, s_count);
  };

  w.at_points.resize(x.rows(), q_count);
  w.params.resize(nominal.size(), q_count);
  // The channels the model gives as built (a linear model's IMU rows are not).
  const Eigen::MatrixXd& h = loo_observation_;
  const bool loo = design_.hasLeaveOneOut();

  if (!blocked) {
    // kUnsplit. Stage 1 at once; stage 2 drops the unusable points.
    evaluatePoints(0, q_count);
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
      ++report->invalid_points;
      if (report->first_problem.empty()) {
        report->first_problem = "collocation point " + std::to_string(q) + ": " +
                                (w.reasons[q].empty() ? "non-finite state" : w.reasons[q]);
      }
    }
    const Eigen::Index valid = static_cast<Eigen::Index>(w.cols.size());
    w.y.resize(ns, valid);
    if (valid == q_count) {
      w.y = w.at_points.topRows(ns).array();
    } else {
      for (Eigen::Index i = 0; i < valid; ++i)
        w.y.col(i) = w.at_points.col(w.cols[i]).head(ns).array();
    }
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
        integratePoints(params(Eigen::all, cols), y_part);
        work.y.middleCols(begin, count) = y_part;
      });
      integrations_ += static_cast<long>(valid);
    } else if (valid > 0) {
      if (valid == q_count) {
        integratePoints(params, w.y);
      } else {
        integratePoints(params(Eigen::all, w.cols), w.y);
      }
      integrations_ += static_cast<long>(valid);
    }
    const bool integrated_finite = allFiniteFast(w.y);
    for (Eigen::Index i = 0; i < valid && !integrated_finite; ++i) {
      if (w.y.col(i).allFinite()) continue;
      w.usable[w.cols[i]] = false;
      ++report->nonfinite_points;
      if (report->first_problem.empty()) {
        report->first_problem =
            "collocation point " + std::to_string(w.cols[i]) + ": integration not finite";
      }
    }
    if (report->invalid_points == 0 && report->nonfinite_points == 0) {
      // Stage 4, every point usable: one block of all points (the
      // precomputed projector); stage 5 the design's leave-one-out error.
      w.state_sums.resize(ns, s_count);
      projectBlock(0, 0, q_count, w.y.data());
      x.topRows(ns) = sumBlocks(w.state_sums, ns, 0);
      if (loo) report->loo_error = design_.leaveOneOutError(h * w.y.matrix());
      return true;
    }
    // Stage 4 without the unusable points: least squares on the rest.
    Eigen::MatrixXd propagated = Eigen::MatrixXd::Zero(ns, q_count);
    for (Eigen::Index i = 0; i < valid; ++i) {
      if (w.usable[w.cols[i]]) propagated.col(w.cols[i]) = w.y.col(i).matrix();
    }
    x.topRows(ns) = project(propagated, w.usable, report);
    return true;
  }

  // kBlocked.
  const Eigen::Index blocks = (q_count + kBlock - 1) / kBlock;
  const Eigen::MatrixXd& pinv = design_.leastSquaresProjector();
  const Eigen::VectorXd& loo_scale = design_.leaveOneOutScale();
  // The projector is the pseudo-inverse: the channels' fit is H times the
  // states' coefficients, no second sum over the points.
  const bool regression = &pinv == &projector;
  const Eigen::Index nz = loo ? h.rows() : 0;
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
    evaluatePoints(begin, end);  // stage 1
    // Stage 2: any unusable point, and kUnsplit takes over.
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
    integratePoints(part_params, y_part);  // stage 3
    if (!allFiniteFast(y_part)) {
      work.unusable[part] = 1;
      return;
    }
    work.y.middleCols(begin, count) = y_part;
    for (Eigen::Index b = begin / kBlock; b * kBlock < end; ++b) {
      const Eigen::Index q0 = b * kBlock, nq = std::min<Eigen::Index>(kBlock, q_count - q0);
      projectBlock(b, q0, nq, &work.y(0, q0));  // stage 4, this block's sums
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
  x.topRows(ns) = sumBlocks(w.state_sums, ns, 0);
  for (Eigen::Index b = 1; b < blocks; ++b) x.topRows(ns) += sumBlocks(w.state_sums, ns, b);
  if (!loo) return true;

  // Stage 5: the leave-one-out error from the fit of z (as
  // CollocationDesign::leaveOneOutError), per block.
  if (regression) {
    w.coeffs.resize(nz, s_count);
    smallProduct(h.data(), x.data(), 1, x.rows(), w.coeffs.data(), nz, ns, s_count);
  } else {
    w.coeffs = sumBlocks(w.channel_sums, nz, 0);
    for (Eigen::Index b = 1; b < blocks; ++b) w.coeffs += sumBlocks(w.channel_sums, nz, b);
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
