// Reference posterior, docs/method.md §4.6: orchestration of the four steps.
#include "pc_ekf/reference/reference_posterior.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "pc_ekf/reference/posterior_fine_grid.h"
#include "pc_ekf/reference/posterior_mode_search.h"
#include "pc_ekf/reference/posterior_prior.h"

namespace pc_ekf {

namespace {

using Clock = std::chrono::steady_clock;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr Eigen::Index kCoarseBatch = 4096;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

void validate(const PosteriorResidual& residual, const std::vector<GermSpec>& prior,
              const ReferencePosteriorSettings& s) {
  if (residual.dimension() != static_cast<int>(prior.size()) || prior.empty()) {
    throw std::invalid_argument("computeReferencePosterior: residual dimension " +
                                std::to_string(residual.dimension()) + " but " +
                                std::to_string(prior.size()) + " germs");
  }
  if (s.coarse_points < 3 || s.fine_points < 3 || s.bins < 1 || s.max_candidates < 1 ||
      !(s.fine_span_sigmas > 0.0) || !(s.border_mass_tolerance > 0.0) ||
      !(s.mode_log_margin > 0.0)) {
    throw std::invalid_argument(
        "computeReferencePosterior: need coarse_points, fine_points >= 3, bins, max_candidates "
        ">= 1 and positive fine_span_sigmas, border_mass_tolerance, mode_log_margin");
  }
}

// Step (1): log posterior at every coarse node; only nodes of positive prior
// density are evaluated.
Eigen::VectorXd coarseLogPosterior(const PosteriorResidual& residual, const CoarseGrid& grid,
                                   const Eigen::VectorXd* log_likelihood,
                                   const PosteriorProgress& progress) {
  Eigen::VectorXd l = grid.logPrior();
  if (log_likelihood != nullptr) {
    if (log_likelihood->size() != grid.size()) {
      throw std::invalid_argument("computeReferencePosterior: coarse log-likelihood has " +
                                  std::to_string(log_likelihood->size()) + " values for " +
                                  std::to_string(grid.size()) + " nodes");
    }
    l += *log_likelihood;
  } else {
    std::vector<Eigen::Index> live;
    for (Eigen::Index j = 0; j < grid.size(); ++j) {
      if (std::isfinite(l[j])) live.push_back(j);
    }
    for (std::size_t start = 0; start < live.size(); start += kCoarseBatch) {
      const std::size_t end = std::min(live.size(), start + static_cast<std::size_t>(kCoarseBatch));
      Eigen::MatrixXd xi(grid.dimension(), static_cast<Eigen::Index>(end - start));
      for (std::size_t i = start; i < end; ++i) xi.col(i - start) = grid.nodes().col(live[i]);
      const Eigen::VectorXd ll = logLikelihood(residual.residuals(xi));
      for (std::size_t i = start; i < end; ++i) l[live[i]] += ll[i - start];
      if (progress) {
        progress("coarse grid: " + std::to_string(end) + " / " + std::to_string(live.size()) +
                 " nodes");
      }
    }
  }
  for (Eigen::Index j = 0; j < l.size(); ++j) {
    if (!std::isfinite(l[j])) l[j] = -kInf;  // NaN likelihoods too
  }
  return l;
}

// value = nominal (1 + range xi) is affine per parameter (docs/method.md §1.1).
void toParameterUnits(ReferencePosterior& r, const ParameterMapping& mapping) {
  r.names = mapping.names();
  for (int i = 0; i < mapping.count(); ++i) {
    const auto& u = mapping.uncertain()[i];
    const double scale = u.nominal * u.relative_range;
    r.mean[i] = u.nominal + scale * r.xi_mean[i];
    r.stddev[i] = std::abs(scale) * r.xi_stddev[i];
    Histogram& h = r.marginals[i];
    h.edges = (u.nominal + scale * h.edges.array()).matrix();
    h.densities /= std::abs(scale);
    if (scale < 0.0) {
      h.edges.reverseInPlace();
      h.densities.reverseInPlace();
    }
    for (auto& m : r.modes) m.parameters[i] = u.nominal + scale * m.xi[i];
  }
}

}  // namespace

ReferencePosterior computeReferencePosterior(const PosteriorResidual& residual,
                                             const std::vector<GermSpec>& germs,
                                             const ReferencePosteriorSettings& settings,
                                             const Eigen::VectorXd* coarse_log_likelihood,
                                             const PosteriorProgress& progress) {
  const auto start = Clock::now();
  validate(residual, germs, settings);
  const PriorDensity prior(germs);
  const int n = prior.dimension();
  const long simulations_before = residual.simulations();
  ReferencePosterior out;

  // (1) Coarse global grid.
  const CoarseGrid grid(prior, settings.coarse_points);
  out.coarse_grid_size = grid.size();
  const Eigen::VectorXd coarse =
      coarseLogPosterior(residual, grid, coarse_log_likelihood, progress);
  Eigen::Index best = 0;
  out.coarse_best_log_density = coarse.maxCoeff(&best);
  if (!std::isfinite(out.coarse_best_log_density)) {
    throw std::runtime_error(
        "computeReferencePosterior: zero posterior density on every node "
        "of the coarse grid");
  }
  out.coarse_best_xi = grid.nodes().col(best);
  out.coarse_seconds = secondsSince(start);

  // (2) Refine the best local maxima together (one residual batch per iteration).
  const auto refine_start = Clock::now();
  const std::vector<Eigen::Index> maxima = grid.localMaxima(coarse);
  out.coarse_local_maxima = static_cast<int>(maxima.size());
  std::vector<Eigen::VectorXd> starts;
  for (std::size_t i = 0; i < maxima.size() && static_cast<int>(i) < settings.max_candidates; ++i) {
    starts.push_back(grid.nodes().col(maxima[i]));
  }
  out.refined_candidates = static_cast<int>(starts.size());
  std::vector<PosteriorModeEstimate> estimates =
      refineModes(residual, prior, starts, settings.mode_search);
  std::stable_sort(estimates.begin(), estimates.end(),
                   [](const auto& a, const auto& b) { return a.log_density > b.log_density; });
  out.refine_seconds = secondsSince(refine_start);
  if (progress) {
    std::ostringstream s;
    s << "refined " << starts.size() << " of " << maxima.size() << " coarse maxima; best log "
      << "density " << estimates.front().log_density;
    progress(s.str());
  }

  // (3) Fine grid per distinct mode; a maximiser inside an earlier box is the
  // same mode (its mass is already counted there).
  const auto fine_start = Clock::now();
  FineGridSettings fine;
  fine.points = settings.fine_points;
  fine.span_sigmas = settings.fine_span_sigmas;
  fine.border_mass_tolerance = settings.border_mass_tolerance;
  std::vector<FineGridIntegral> grids;
  std::vector<FineGridBox> boxes;
  std::vector<const PosteriorModeEstimate*> kept;
  for (const auto& e : estimates) {
    if (e.log_density < estimates.front().log_density - settings.mode_log_margin) break;
    if (e.duplicate_of >= 0) continue;
    bool seen = false;
    for (const auto& b : boxes) seen = seen || b.contains(e.xi);
    if (seen) continue;
    grids.push_back(integrateMode(residual, prior, e, boxes, fine, progress));
    boxes.push_back(grids.back().box);
    kept.push_back(&e);
  }
  out.fine_seconds = secondsSince(fine_start);

  // (4) Combine: masses relative to a common reference (log-sum-exp).
  double reference = -kInf;
  for (const auto& g : grids) reference = std::max(reference, g.log_mass);
  if (!std::isfinite(reference)) {
    throw std::runtime_error("computeReferencePosterior: no mass on any fine grid");
  }
  double total = 0.0, border = 0.0;
  for (const auto& g : grids) {
    const double m = std::isfinite(g.log_mass) ? std::exp(g.log_mass - reference) : 0.0;
    total += m;
    border += m * g.border_fraction;
  }
  out.log_mass = reference + std::log(total);
  out.border_mass = border / total;
  for (std::size_t i = 0; i < grids.size(); ++i) {
    ReferencePosteriorMode m;
    m.xi = kept[i]->xi;
    m.parameters = m.xi;
    m.log_density = kept[i]->log_density;
    m.mass_fraction =
        std::isfinite(grids[i].log_mass) ? std::exp(grids[i].log_mass - reference) / total : 0.0;
    m.border_fraction = grids[i].border_fraction;
    m.principal_stddev = grids[i].principal_stddev;
    m.enlargements = grids[i].enlargements;
    m.converged = kept[i]->converged;
    out.modes.push_back(m);
  }
  std::stable_sort(out.modes.begin(), out.modes.end(),
                   [](const auto& a, const auto& b) { return a.mass_fraction > b.mass_fraction; });
  posteriorMoments(grids, out.xi_mean, out.xi_covariance);
  out.xi_stddev = out.xi_covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  for (int i = 0; i < n; ++i) {
    out.names.push_back("xi" + std::to_string(i + 1));
    out.marginals.push_back(marginalHistogram(grids, prior, i, settings.bins));
  }
  out.mean = out.xi_mean;
  out.stddev = out.xi_stddev;
  out.simulations = residual.simulations() - simulations_before;
  out.total_seconds = secondsSince(start);
  return out;
}

ReferencePosterior computeReferencePosterior(
    const MechanicalModel& model, const ParameterMapping& mapping, const MeasurementSeries& series,
    const NoiseModel& noise, const IntegratorSettings& integration,
    const ReferencePosteriorSettings& settings, const CoarseGridCache* cache,
    const PosteriorProgress& progress) {
  const ModelPosteriorResidual residual(model, mapping, series, noise, integration,
                                        settings.threads);
  Eigen::VectorXd cached;
  if (cache != nullptr) {
    cache->checkCompatible(mapping, residual.times(), integration, settings.coarse_points);
    cached = cache->logLikelihood(series, noise);
  }
  ReferencePosterior out = computeReferencePosterior(
      residual, mapping.germs(), settings, cache != nullptr ? &cached : nullptr, progress);
  if (cache != nullptr) out.cached_simulations = cache->simulations();
  toParameterUnits(out, mapping);
  return out;
}

}  // namespace pc_ekf
