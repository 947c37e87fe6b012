// Hamiltonian Monte Carlo with finite-difference gradients: see mcmc_samplers.h.
#include <cmath>
#include <string>

#include "pc_ekf/reference/mcmc_samplers.h"
#include "pc_ekf/reference/posterior_mode_search.h"

namespace pc_ekf {

namespace {

constexpr double kTargetAcceptance = 0.8;  // Stan's default: a curved ridge needs small steps
constexpr double kTrajectoryLength = 1.5;  // in posterior std (the metric's units)
constexpr int kMaxLeapfrogSteps = 200;

// F = -log posterior and its gradient at each point, one residual batch.
void evaluate(const PosteriorResidual& residual, const PriorDensity& prior,
              const std::vector<Eigen::VectorXd>& points, double step, std::vector<double>& f,
              std::vector<Eigen::VectorXd>& gradient) {
  std::vector<Linearisation> lin = linearise(residual, prior, points, step);
  f.resize(points.size());
  gradient.resize(points.size());
  Eigen::VectorXd prior_gradient, curvature;
  for (std::size_t k = 0; k < lin.size(); ++k) {
    f[k] = lin[k].f;
    if (!std::isfinite(f[k])) continue;
    prior.derivatives(lin[k].x, prior_gradient, curvature);
    gradient[k] = lin[k].jacobian.transpose() * lin[k].r - prior_gradient;
  }
}

}  // namespace

SamplerRun runHamiltonian(const PosteriorResidual& residual, const PriorDensity& prior,
                          const Eigen::MatrixXd& start, const Eigen::MatrixXd& covariance,
                          const McmcSettings& settings, std::mt19937_64& rng,
                          const PosteriorProgress& progress) {
  const int n = prior.dimension(), chains = static_cast<int>(start.cols());
  const double fd_step = settings.mode_search.difference_step;
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> uniform;
  std::vector<Eigen::VectorXd> q(chains), grad;
  std::vector<double> f;
  for (int c = 0; c < chains; ++c) q[c] = start.col(c);
  evaluate(residual, prior, q, fd_step, f, grad);
  Eigen::MatrixXd metric = covariance;  // inverse mass matrix: the posterior covariance
  Eigen::MatrixXd factor = choleskyFactor(metric);
  SamplerRun out;
  const int kept = settings.samples / settings.thin;
  out.draws.assign(chains, Eigen::MatrixXd(n, kept));
  std::vector<Eigen::MatrixXd> history(chains, Eigen::MatrixXd(n, settings.burn_in));
  double log_eps = std::log(0.5);
  long accepted_window = 0, accepted_kept = 0;
  const int total = settings.burn_in + settings.samples;
  Eigen::VectorXd z(n);
  for (int it = 0; it < total; ++it) {
    // A jittered step keeps trajectories from resonating with a period of the target.
    const double eps = std::exp(log_eps) * (0.8 + 0.4 * uniform(rng));
    const int steps = std::min(kMaxLeapfrogSteps, static_cast<int>(std::ceil(kTrajectoryLength / eps)));
    std::vector<Eigen::VectorXd> p(chains), x = q, g = grad;
    std::vector<double> h0(chains);
    std::vector<bool> alive(chains, true);
    for (int c = 0; c < chains; ++c) {
      for (int i = 0; i < n; ++i) z[i] = normal(rng);
      p[c] = factor.transpose().triangularView<Eigen::Upper>().solve(z);  // N(0, metric^-1)
      h0[c] = f[c] + 0.5 * p[c].dot(metric * p[c]);
      p[c] -= 0.5 * eps * g[c];
    }
    std::vector<double> fx(chains);
    for (int s = 1; s <= steps; ++s) {
      std::vector<Eigen::VectorXd> points;
      std::vector<int> owner;
      for (int c = 0; c < chains; ++c) {
        if (!alive[c]) continue;
        x[c] += eps * (metric * p[c]);
        if (!std::isfinite(prior.logDensity(x[c]))) {
          alive[c] = false;  // left the support: the trajectory is refused
          continue;
        }
        points.push_back(x[c]);
        owner.push_back(c);
      }
      std::vector<double> fs;
      std::vector<Eigen::VectorXd> gs;
      evaluate(residual, prior, points, fd_step, fs, gs);
      for (std::size_t k = 0; k < points.size(); ++k) {
        const int c = owner[k];
        if (!std::isfinite(fs[k])) {
          alive[c] = false;
          continue;
        }
        fx[c] = fs[k];
        g[c] = gs[k];
        p[c] -= (s == steps ? 0.5 : 1.0) * eps * g[c];
      }
    }
    long accepted = 0;
    for (int c = 0; c < chains; ++c) {
      if (!alive[c]) continue;
      const double h1 = fx[c] + 0.5 * p[c].dot(metric * p[c]);
      if (std::log(uniform(rng)) < h0[c] - h1) {
        q[c] = x[c];
        f[c] = fx[c];
        grad[c] = g[c];
        ++accepted;
      }
    }
    if (it < settings.burn_in) {
      accepted_window += accepted;
      for (int c = 0; c < chains; ++c) history[c].col(it) = q[c];
    } else {
      accepted_kept += accepted;
      const int k = it - settings.burn_in;
      if (k % settings.thin == 0 && k / settings.thin < kept) {
        for (int c = 0; c < chains; ++c) out.draws[c].col(k / settings.thin) = q[c];
      }
    }
    if (it < settings.burn_in && (it + 1) % settings.adapt_every == 0) {
      const double rate = static_cast<double>(accepted_window) / (settings.adapt_every * chains);
      accepted_window = 0;
      const double gain = 1.0 / std::sqrt(static_cast<double>((it + 1) / settings.adapt_every));
      log_eps += 2.0 * gain * (rate - kTargetAcceptance);
      Eigen::MatrixXd cov;
      if (burnInCovariance(history, it + 1, cov)) {
        metric = cov;
        factor = choleskyFactor(metric);
      }
      if (progress) {
        progress("burn-in " + std::to_string(it + 1) + "/" + std::to_string(settings.burn_in) +
                 " (Hamiltonian), acceptance " + std::to_string(rate) + ", step " +
                 std::to_string(std::exp(log_eps)) + " x " + std::to_string(steps));
      }
    }
    if (progress && it >= settings.burn_in && (it + 1 - settings.burn_in) % 100 == 0) {
      progress("sampling " + std::to_string(it + 1 - settings.burn_in) + "/" +
               std::to_string(settings.samples) + " (Hamiltonian)");
    }
  }
  out.acceptance = static_cast<double>(accepted_kept) /
                   (static_cast<double>(settings.samples) * static_cast<double>(chains));
  out.scale = std::exp(log_eps);
  return out;
}

}  // namespace pc_ekf
