// Sampling reference posterior: see mcmc_reference.h.
#include "pc_ekf/reference/mcmc_reference.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>

#include "pc_ekf/reference/mcmc_samplers.h"
#include "pc_ekf/reference/posterior_prior.h"

namespace pc_ekf {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

void validate(const PosteriorResidual& residual, const std::vector<GermSpec>& prior,
              const std::vector<Eigen::VectorXd>& starts, const McmcSettings& s) {
  const int n = residual.dimension();
  if (n != static_cast<int>(prior.size()) || prior.empty()) {
    throw std::invalid_argument("runMcmcReference: residual dimension " + std::to_string(n) +
                                " but " + std::to_string(prior.size()) + " germs");
  }
  if (starts.empty()) throw std::invalid_argument("runMcmcReference: no start point");
  for (const auto& x : starts) {
    if (x.size() != n) throw std::invalid_argument("runMcmcReference: start of wrong size");
  }
  if (s.chains < 2 || s.thin < 1 || s.samples < 8 * s.thin || !(s.start_spread >= 0.0)) {
    throw std::invalid_argument(
        "runMcmcReference: need chains >= 2, thin >= 1, samples >= 8 thin and start_spread >= 0");
  }
  if (s.sampler == McmcSampler::kConditionalLaplace) {
    if (s.ridge_dimensions < -1 || s.ridge_dimensions > 3 || s.ridge_dimensions > n ||
        (s.grid_points != 0 && s.grid_points < 3) || !(s.grid_drop > 0.0)) {
      throw std::invalid_argument(
          "runMcmcReference: the conditional Laplace needs ridge_dimensions -1 (automatic) or in "
          "[0, min(3, n)], "
          "grid_points >= 3 and grid_drop > 0");
    }
  } else if (s.sampler == McmcSampler::kEnsemble) {
    if (s.chains % 2 != 0 || s.chains < 2 * n || !(s.stretch > 1.0) || s.burn_in < 0) {
      throw std::invalid_argument(
          "runMcmcReference: the ensemble needs an even number of walkers (chains) >= 2 n = " +
          std::to_string(2 * n) + ", stretch > 1 and burn_in >= 0");
    }
  } else if (s.burn_in < 2 * s.adapt_every || s.adapt_every < 1 ||
             (s.sampler == McmcSampler::kAdaptiveMetropolis &&
              !(s.target_acceptance > 0.0 && s.target_acceptance < 1.0))) {
    throw std::invalid_argument(
        "runMcmcReference: need adapt_every >= 1, burn_in >= 2 adapt_every and "
        "target_acceptance in (0, 1)");
  }
}

// Splits every chain in two halves (rows: chains, columns: iterations).
Eigen::MatrixXd splitChains(const Eigen::MatrixXd& chains) {
  const Eigen::Index half = chains.cols() / 2;
  Eigen::MatrixXd out(2 * chains.rows(), half);
  out.topRows(chains.rows()) = chains.leftCols(half);
  out.bottomRows(chains.rows()) = chains.middleCols(chains.cols() - half, half);
  return out;
}

struct ChainVariances {
  double within = 0.0;  // W: mean within-chain variance (1 / (N - 1))
  double plus = 0.0;    // var+ = (N - 1) / N W + B / N
};

ChainVariances chainVariances(const Eigen::MatrixXd& c) {
  const double n = static_cast<double>(c.cols());
  const Eigen::VectorXd means = c.rowwise().mean();
  double w = 0.0;
  for (Eigen::Index m = 0; m < c.rows(); ++m) {
    w += (c.row(m).array() - means[m]).square().sum() / (n - 1.0);
  }
  w /= static_cast<double>(c.rows());
  const double b_over_n = (means.array() - means.mean()).square().sum() / (c.rows() - 1.0);
  return {w, (n - 1.0) / n * w + b_over_n};
}

// One generator and its distributions for the whole run: normal_distribution
// keeps its second variate, so sharing the objects keeps the draws of the
// adaptive Metropolis as they were before the samplers were split.
struct Random {
  explicit Random(std::uint64_t seed) : rng(seed) {}
  Eigen::MatrixXd gaussian(Eigen::Index rows, Eigen::Index cols) {
    Eigen::MatrixXd z(rows, cols);
    for (Eigen::Index j = 0; j < cols; ++j) {
      for (Eigen::Index i = 0; i < rows; ++i) z(i, j) = normal(rng);
    }
    return z;
  }
  std::mt19937_64 rng;
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> uniform;
};

// (3) Burn-in with adaptation, then frozen proposal; fills out's draws,
// acceptance and proposal_scale.
void runAdaptiveMetropolis(const PosteriorResidual& residual, const PriorDensity& prior,
                           Eigen::MatrixXd x, Eigen::VectorXd logp, Eigen::MatrixXd proposal_factor,
                           const McmcSettings& settings, Random& random,
                           const PosteriorProgress& progress, McmcReference& out) {
  const int n = prior.dimension(), chains = settings.chains;
  const double optimal = 2.38 / std::sqrt(static_cast<double>(n));
  double log_factor = 0.0;
  std::vector<Eigen::MatrixXd> history(chains, Eigen::MatrixXd(n, settings.burn_in));
  out.draws.assign(chains, Eigen::MatrixXd(n, settings.samples / settings.thin));
  long accepted_window = 0, accepted_kept = 0;
  const int total = settings.burn_in + settings.samples;
  for (int it = 0; it < total; ++it) {
    const double scale = optimal * std::exp(log_factor);
    const Eigen::MatrixXd y = x + scale * proposal_factor * random.gaussian(n, chains);
    const Eigen::VectorXd logq = logPosterior(residual, prior, y);
    for (int c = 0; c < chains; ++c) {
      if (std::isfinite(logq[c]) && std::log(random.uniform(random.rng)) < logq[c] - logp[c]) {
        x.col(c) = y.col(c);
        logp[c] = logq[c];
        if (it < settings.burn_in) {
          ++accepted_window;
        } else {
          ++accepted_kept;
        }
      }
      if (it < settings.burn_in) {
        history[c].col(it) = x.col(c);
      } else if ((it - settings.burn_in) % settings.thin == 0 &&
                 (it - settings.burn_in) / settings.thin < out.draws[c].cols()) {
        out.draws[c].col((it - settings.burn_in) / settings.thin) = x.col(c);
      }
    }
    if (it < settings.burn_in && (it + 1) % settings.adapt_every == 0) {
      const double rate = static_cast<double>(accepted_window) / (settings.adapt_every * chains);
      accepted_window = 0;
      const double step = 1.0 / std::sqrt(static_cast<double>((it + 1) / settings.adapt_every));
      log_factor += 2.0 * step * (rate - settings.target_acceptance);
      Eigen::MatrixXd cov;
      if (burnInCovariance(history, it + 1, cov)) proposal_factor = choleskyFactor(cov);
      if (progress) {
        std::ostringstream s;
        s << "burn-in " << it + 1 << "/" << settings.burn_in << ", acceptance " << rate;
        progress(s.str());
      }
    }
    if (progress && it >= settings.burn_in && (it + 1 - settings.burn_in) % 1000 == 0) {
      progress("sampling " + std::to_string(it + 1 - settings.burn_in) + "/" +
               std::to_string(settings.samples));
    }
  }
  out.acceptance =
      static_cast<double>(accepted_kept) / (static_cast<double>(settings.samples) * chains);
  out.proposal_scale = std::exp(log_factor);

}

// (4) Statistics of the kept draws, over the chains (or walkers).
void summarise(McmcReference& out) {
  const int chains = static_cast<int>(out.draws.size());
  const Eigen::Index n = out.draws.front().rows(), kept = out.draws.front().cols();
  Eigen::MatrixXd pooled(n, kept * chains);
  for (int c = 0; c < chains; ++c) pooled.middleCols(c * kept, kept) = out.draws[c];
  out.xi_mean = pooled.rowwise().mean();
  const Eigen::MatrixXd centred = pooled.colwise() - out.xi_mean;
  out.xi_covariance = centred * centred.transpose() / (pooled.cols() - 1.0);
  out.xi_stddev = out.xi_covariance.diagonal().cwiseSqrt();
  out.r_hat.resize(n);
  out.effective_size.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    Eigen::MatrixXd one(chains, kept);
    for (int c = 0; c < chains; ++c) one.row(c) = out.draws[c].row(i);
    out.r_hat[i] = splitRHat(one);
    out.effective_size[i] = effectiveSampleSize(one);
    out.names.push_back("xi" + std::to_string(i + 1));
  }
  out.mean = out.xi_mean;
  out.stddev = out.xi_stddev;
  out.mean_error = (out.stddev.array() / out.effective_size.array().sqrt()).matrix();
}

}  // namespace

// Log posterior per column; columns outside the prior's support are not simulated.
Eigen::VectorXd logPosterior(const PosteriorResidual& residual, const PriorDensity& prior,
                             const Eigen::MatrixXd& xi) {
  Eigen::VectorXd out = prior.logDensities(xi);
  std::vector<Eigen::Index> live;
  for (Eigen::Index j = 0; j < xi.cols(); ++j) {
    if (std::isfinite(out[j])) live.push_back(j);
  }
  if (live.empty()) return out;
  Eigen::MatrixXd batch(xi.rows(), static_cast<Eigen::Index>(live.size()));
  for (std::size_t i = 0; i < live.size(); ++i) batch.col(i) = xi.col(live[i]);
  const Eigen::VectorXd ll = logLikelihood(residual.residuals(batch));
  for (std::size_t i = 0; i < live.size(); ++i) out[live[i]] += ll[i];
  for (Eigen::Index j = 0; j < out.size(); ++j) {
    if (!std::isfinite(out[j])) out[j] = -kInf;
  }
  return out;
}

// The ridge helps where the data pin a parameter far tighter than the others.
Eigen::MatrixXd choleskyFactor(Eigen::MatrixXd cov) {
  cov = 0.5 * (cov + cov.transpose());
  const double ridge = 1e-12 * std::max(cov.diagonal().maxCoeff(), 1e-300);
  for (int attempt = 0; attempt < 8; ++attempt) {
    Eigen::LLT<Eigen::MatrixXd> llt(cov);
    if (llt.info() == Eigen::Success) return llt.matrixL();
    cov.diagonal().array() += ridge * std::pow(100.0, attempt);
  }
  throw std::runtime_error("runMcmcReference: proposal covariance is not positive definite");
}

bool burnInCovariance(const std::vector<Eigen::MatrixXd>& history, int iterations,
                      Eigen::MatrixXd& cov) {
  const int chains = static_cast<int>(history.size());
  const Eigen::Index n = history.front().rows();
  const int from = iterations / 2, count = iterations - from;
  if (count * chains <= 10 * n) return false;
  Eigen::MatrixXd pooled(n, static_cast<Eigen::Index>(count) * chains);
  for (int c = 0; c < chains; ++c)
    pooled.middleCols(c * count, count) = history[c].middleCols(from, count);
  const Eigen::MatrixXd centred = pooled.colwise() - pooled.rowwise().mean();
  cov = centred * centred.transpose() / (pooled.cols() - 1.0);
  return cov.allFinite() && cov.diagonal().minCoeff() > 0.0;
}

double splitRHat(const Eigen::MatrixXd& chains) {
  if (chains.rows() < 1 || chains.cols() < 4) {
    throw std::invalid_argument("splitRHat: need >= 1 chain of >= 4 iterations");
  }
  const ChainVariances v = chainVariances(splitChains(chains));
  if (!(v.within > 0.0)) return v.plus > 0.0 ? kInf : 1.0;
  return std::sqrt(v.plus / v.within);
}

double effectiveSampleSize(const Eigen::MatrixXd& chains) {
  if (chains.rows() < 1 || chains.cols() < 4) {
    throw std::invalid_argument("effectiveSampleSize: need >= 1 chain of >= 4 iterations");
  }
  const Eigen::MatrixXd c = splitChains(chains);
  const Eigen::Index m = c.rows(), n = c.cols();
  const ChainVariances v = chainVariances(c);
  if (!(v.plus > 0.0)) return static_cast<double>(m * n);
  const Eigen::MatrixXd centred = c.colwise() - c.rowwise().mean();
  // rho_t = 1 - (W - mean autocovariance at lag t) / var+ (autocovariances / N).
  auto rho = [&](Eigen::Index t) {
    double acov = 0.0;
    for (Eigen::Index k = 0; k < m; ++k) {
      acov += centred.row(k).head(n - t).dot(centred.row(k).tail(n - t)) / static_cast<double>(n);
    }
    return 1.0 - (v.within - acov / static_cast<double>(m)) / v.plus;
  };
  // Geyer's initial monotone sequence over pairs (rho_2k + rho_2k+1).
  double tau = -1.0, previous = kInf;
  for (Eigen::Index t = 0; t + 1 < n; t += 2) {
    double pair = (t == 0 ? 1.0 : rho(t)) + rho(t + 1);
    if (!(pair > 0.0)) break;
    pair = std::min(pair, previous);
    previous = pair;
    tau += 2.0 * pair;
  }
  tau = std::max(tau, 1.0 / std::log10(static_cast<double>(m * n)));  // antithetic cap (Stan)
  return static_cast<double>(m * n) / tau;
}

McmcReference runMcmcReference(const PosteriorResidual& residual,
                               const std::vector<GermSpec>& germs,
                               const std::vector<Eigen::VectorXd>& starts,
                               const McmcSettings& settings, const PosteriorProgress& progress) {
  const auto start_time = std::chrono::steady_clock::now();
  validate(residual, germs, starts, settings);
  const PriorDensity prior(germs);
  const int n = prior.dimension(), chains = settings.chains;
  const long simulations_before = residual.simulations();
  McmcReference out;

  // (1) Mode and Laplace covariance.
  std::vector<Eigen::VectorXd> clamped;
  for (const auto& x : starts) clamped.push_back(prior.clamp(x));
  const std::vector<PosteriorModeEstimate> modes =
      refineModes(residual, prior, clamped, settings.mode_search);
  const PosteriorModeEstimate* best = &modes.front();
  for (const auto& e : modes) {
    if (e.log_density > best->log_density) best = &e;
  }
  if (!std::isfinite(best->log_density)) {
    throw std::runtime_error("runMcmcReference: zero posterior density at every start");
  }
  out.mode_xi = best->xi;
  out.mode_log_density = best->log_density;
  for (const auto& e : modes) {
    out.competing_modes +=
        &e != best && e.duplicate_of < 0 && e.log_density > best->log_density - 50.0;
  }
  const Eigen::MatrixXd laplace = best->hessian.inverse();
  out.laplace_xi_stddev = laplace.diagonal().cwiseMax(0.0).cwiseSqrt();
  out.laplace_xi_covariance = laplace;
  Eigen::MatrixXd proposal_factor = choleskyFactor(laplace);

  if (settings.sampler == McmcSampler::kConditionalLaplace) {
    std::mt19937_64 rng(settings.seed);
    ImportanceRun run = runConditionalLaplace(residual, prior, *best, settings, rng, progress);
    out.draws = std::move(run.draws);
    out.xi_mean = run.mean;
    out.xi_covariance = run.covariance;
    out.xi_stddev = run.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
    out.r_hat = run.r_hat;
    out.effective_size = run.effective_size;
    for (int i = 0; i < n; ++i) out.names.push_back("xi" + std::to_string(i + 1));
    out.mean = out.xi_mean;
    out.stddev = out.xi_stddev;
    out.mean_error = (out.stddev.array() / out.effective_size.array().sqrt()).matrix();
    out.acceptance = run.efficiency;
    out.importance_ess = run.kish;
    out.largest_weight = run.largest_weight;
    out.ridge_nodes = run.nodes;
    out.simulations = residual.simulations() - simulations_before;
    out.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
    return out;
  }

  // (2) Over-dispersed starts with finite density.
  Random random(settings.seed);
  Eigen::MatrixXd x =
      (settings.start_spread * proposal_factor * random.gaussian(n, chains)).colwise() +
      out.mode_xi;
  Eigen::VectorXd logp = logPosterior(residual, prior, x);
  for (int attempt = 0; attempt < 20 && !logp.allFinite(); ++attempt) {
    for (int c = 0; c < chains; ++c) {
      if (std::isfinite(logp[c])) continue;
      x.col(c) = out.mode_xi + 0.5 * (x.col(c) - out.mode_xi);  // halfway back to the mode
    }
    logp = logPosterior(residual, prior, x);
  }
  for (int c = 0; c < chains; ++c) {
    if (!std::isfinite(logp[c])) {
      x.col(c) = out.mode_xi;
      logp[c] = best->log_density;
    }
  }

  if (settings.sampler == McmcSampler::kEnsemble) {
    SamplerRun run = runStretchMove(
        [&](const Eigen::MatrixXd& y) { return logPosterior(residual, prior, y); }, x, logp,
        settings, random.rng, progress);
    out.draws = std::move(run.draws);
    out.acceptance = run.acceptance;
    out.proposal_scale = run.scale;
  } else if (settings.sampler == McmcSampler::kHamiltonian) {
    SamplerRun run = runHamiltonian(residual, prior, x, laplace, settings, random.rng, progress);
    out.draws = std::move(run.draws);
    out.acceptance = run.acceptance;
    out.proposal_scale = run.scale;
  } else {
    runAdaptiveMetropolis(residual, prior, x, logp, proposal_factor, settings, random, progress,
                          out);
  }
  summarise(out);
  out.simulations = residual.simulations() - simulations_before;
  out.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
  return out;
}

McmcReference runMcmcReference(const MechanicalModel& model, const ParameterMapping& mapping,
                               const MeasurementSeries& series, const NoiseModel& noise,
                               const IntegratorSettings& integration, int threads,
                               const std::vector<Eigen::VectorXd>& starts,
                               const McmcSettings& settings, const PosteriorProgress& progress) {
  const ModelPosteriorResidual residual(model, mapping, series, noise, integration, threads);
  McmcReference out = runMcmcReference(residual, mapping.germs(), starts, settings, progress);
  // value = nominal (1 + range xi) is affine per parameter (docs/method.md §1.1).
  out.names = mapping.names();
  for (int i = 0; i < mapping.count(); ++i) {
    const auto& u = mapping.uncertain()[i];
    const double scale = u.nominal * u.relative_range;
    out.mean[i] = u.nominal + scale * out.xi_mean[i];
    out.stddev[i] = std::abs(scale) * out.xi_stddev[i];
    out.mean_error[i] *= std::abs(scale);
  }
  return out;
}

}  // namespace pc_ekf
