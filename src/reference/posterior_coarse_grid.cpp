#include "pc_ekf/reference/posterior_coarse_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "pc_ekf/filter/posterior_residual.h"
#include "pc_ekf/filter/trajectory_simulation.h"

namespace pc_ekf {

namespace {

// Batches of this many columns per thread keep the integrator's stage arrays
// in cache and give the progress callback something to report.
constexpr Eigen::Index kColumnsPerThread = 1024;

bool sameGerm(const GermSpec& a, const GermSpec& b) {
  return a.family == b.family && a.alpha == b.alpha && a.beta == b.beta;
}

}  // namespace

CoarseGrid::CoarseGrid(const PriorDensity& prior, int points_per_axis) : points_(points_per_axis) {
  if (points_ < kMinPoints) {
    throw std::invalid_argument("CoarseGrid: need at least " + std::to_string(kMinPoints) +
                                " points per axis");
  }
  const int n = prior.dimension();
  Eigen::Index size = 1;
  for (int i = 0; i < n; ++i) size *= points_;
  nodes_.resize(n, size);
  for (Eigen::Index j = 0; j < size; ++j) {
    Eigen::Index rest = j;
    for (int i = 0; i < n; ++i) {
      const GermInterval& r = prior.gridRange(i);
      const Eigen::Index k = rest % points_;
      rest /= points_;
      // Exact ends, so a bounded support's edge nodes are exactly on it.
      nodes_(i, j) = (k == points_ - 1) ? r.upper : r.lower + r.width() * k / (points_ - 1);
    }
  }
  log_prior_ = prior.logDensities(nodes_);
}

std::vector<Eigen::Index> CoarseGrid::localMaxima(const Eigen::VectorXd& values) const {
  if (values.size() != size()) throw std::invalid_argument("CoarseGrid::localMaxima: wrong size");
  const int n = dimension();
  Eigen::Index offsets = 1;
  for (int i = 0; i < n; ++i) offsets *= 3;
  std::vector<Eigen::Index> maxima;
  std::vector<Eigen::Index> index(n);
  for (Eigen::Index j = 0; j < size(); ++j) {
    if (!std::isfinite(values[j])) continue;
    Eigen::Index rest = j;
    for (int i = 0; i < n; ++i, rest /= points_) index[i] = rest % points_;
    bool is_max = true;
    for (Eigen::Index o = 0; o < offsets && is_max; ++o) {
      Eigen::Index code = o, neighbour = 0, stride = 1;
      bool inside = true, self = true;
      for (int i = 0; i < n; ++i, code /= 3, stride *= points_) {
        const Eigen::Index d = code % 3 - 1;
        self = self && d == 0;
        const Eigen::Index k = index[i] + d;
        inside = inside && k >= 0 && k < points_;
        neighbour += k * stride;
      }
      if (!self && inside && values[neighbour] > values[j]) is_max = false;
    }
    if (is_max) maxima.push_back(j);
  }
  std::stable_sort(maxima.begin(), maxima.end(),
                   [&](Eigen::Index a, Eigen::Index b) { return values[a] > values[b]; });
  return maxima;
}

CoarseGridCache::CoarseGridCache(const MechanicalModel& model, const ParameterMapping& mapping,
                                 std::vector<double> times, const IntegratorSettings& integration,
                                 int coarse_points, int threads, const PosteriorProgress& progress)
    : uncertain_(mapping.uncertain()),
      times_(std::move(times)),
      integration_(integration),
      grid_(PriorDensity(mapping.germs()), coarse_points) {
  const Eigen::Index channels = model.observationMatrix().rows();
  channels_.assign(
      times_.size(),
      Eigen::MatrixXd::Constant(channels, grid_.size(), std::numeric_limits<double>::quiet_NaN()));
  std::vector<Eigen::Index> live;
  for (Eigen::Index j = 0; j < grid_.size(); ++j) {
    if (std::isfinite(grid_.logPrior()[j])) live.push_back(j);
  }
  const Eigen::Index chunk = kColumnsPerThread * std::max(1, threads);
  for (std::size_t start = 0; start < live.size(); start += chunk) {
    const std::size_t end = std::min(live.size(), start + static_cast<std::size_t>(chunk));
    Eigen::MatrixXd xi(grid_.dimension(), static_cast<Eigen::Index>(end - start));
    for (std::size_t i = start; i < end; ++i) xi.col(i - start) = grid_.nodes().col(live[i]);
    const auto sim =
        simulateGermChannels(model, mapping, xi, times_, integration, threads, &simulations_);
    for (std::size_t k = 0; k < times_.size(); ++k) {
      for (std::size_t i = start; i < end; ++i) channels_[k].col(live[i]) = sim[k].col(i - start);
    }
    if (progress) {
      progress("coarse grid cache: " + std::to_string(end) + " / " + std::to_string(live.size()) +
               " nodes simulated");
    }
  }
}

void CoarseGridCache::checkCompatible(const ParameterMapping& mapping,
                                      const std::vector<double>& times,
                                      const IntegratorSettings& integration,
                                      int coarse_points) const {
  const auto& u = mapping.uncertain();
  if (u.size() != uncertain_.size()) {
    throw std::invalid_argument("CoarseGridCache: built for " + std::to_string(uncertain_.size()) +
                                " uncertain parameters, not " + std::to_string(u.size()));
  }
  for (std::size_t i = 0; i < u.size(); ++i) {
    if (u[i].name != uncertain_[i].name || u[i].nominal != uncertain_[i].nominal ||
        u[i].relative_range != uncertain_[i].relative_range ||
        !sameGerm(u[i].germ, uncertain_[i].germ)) {
      throw std::invalid_argument("CoarseGridCache: uncertain parameter " + std::to_string(i) +
                                  " ('" + u[i].name + "') differs from the cached one");
    }
  }
  if (times != times_) throw std::invalid_argument("CoarseGridCache: sample times differ");
  if (integration.max_step != integration_.max_step) {
    throw std::invalid_argument("CoarseGridCache: integration max_step differs");
  }
  if (integration.method != integration_.method) {
    throw std::invalid_argument("CoarseGridCache: integration method differs");
  }
  if (coarse_points != grid_.pointsPerAxis()) {
    throw std::invalid_argument("CoarseGridCache: built with " +
                                std::to_string(grid_.pointsPerAxis()) + " points per axis, not " +
                                std::to_string(coarse_points));
  }
}

Eigen::VectorXd CoarseGridCache::logLikelihood(const MeasurementSeries& series,
                                               const NoiseModel& noise) const {
  if (sampleTimes(series) != times_) {
    throw std::invalid_argument(
        "CoarseGridCache: the series' sample times differ from the cache's");
  }
  return pc_ekf::logLikelihood(whitenedResiduals(series, noise, channels_));
}

}  // namespace pc_ekf
