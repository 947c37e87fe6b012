// Stretch-move ensemble sampler: see mcmc_samplers.h.
#include "pc_ekf/reference/mcmc_samplers.h"

#include <cmath>
#include <string>

namespace pc_ekf {

SamplerRun runStretchMove(const LogDensityBatch& log_density, Eigen::MatrixXd x,
                          Eigen::VectorXd logp, const McmcSettings& settings, std::mt19937_64& rng,
                          const PosteriorProgress& progress) {
  const Eigen::Index n = x.rows(), walkers = x.cols(), half = walkers / 2;
  const double a = settings.stretch;
  std::uniform_real_distribution<double> uniform;
  std::uniform_int_distribution<Eigen::Index> partner(0, half - 1);
  SamplerRun out;
  const int kept = settings.samples / settings.thin;
  out.draws.assign(walkers, Eigen::MatrixXd(n, kept));
  long accepted = 0;
  Eigen::MatrixXd y(n, half);
  Eigen::VectorXd log_z(half);
  const int total = settings.burn_in + settings.samples;
  for (int it = 0; it < total; ++it) {
    for (Eigen::Index part = 0; part < 2; ++part) {
      const Eigen::Index moving = part * half, other = (1 - part) * half;
      for (Eigen::Index j = 0; j < half; ++j) {
        // Inverse CDF of g(z) ∝ 1/sqrt(z) on [1/a, a].
        const double z = std::pow((a - 1.0) * uniform(rng) + 1.0, 2) / a;
        log_z[j] = std::log(z);
        const auto c = x.col(other + partner(rng));
        y.col(j) = c + z * (x.col(moving + j) - c);
      }
      const Eigen::VectorXd logq = log_density(y);
      for (Eigen::Index j = 0; j < half; ++j) {
        const double log_ratio = static_cast<double>(n - 1) * log_z[j] + logq[j] - logp[moving + j];
        if (std::isfinite(logq[j]) && std::log(uniform(rng)) < log_ratio) {
          x.col(moving + j) = y.col(j);
          logp[moving + j] = logq[j];
          accepted += it >= settings.burn_in;
        }
      }
    }
    const int k = it - settings.burn_in;
    if (k >= 0 && k % settings.thin == 0 && k / settings.thin < kept) {
      for (Eigen::Index w = 0; w < walkers; ++w) out.draws[w].col(k / settings.thin) = x.col(w);
    }
    if (progress && (it + 1) % 1000 == 0) {
      progress((it < settings.burn_in ? "burn-in " : "sampling ") + std::to_string(it + 1) + "/" +
               std::to_string(total) + " (ensemble)");
    }
  }
  out.acceptance = static_cast<double>(accepted) /
                   (static_cast<double>(settings.samples) * static_cast<double>(walkers));
  out.scale = a;
  return out;
}

}  // namespace pc_ekf
