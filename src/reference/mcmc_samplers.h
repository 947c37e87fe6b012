// The samplers of runMcmcReference (mcmc_reference.h) beside its adaptive
// Metropolis: an affine-invariant ensemble and Hamiltonian Monte Carlo.
//
// kEnsemble: Goodman & Weare's (2010) stretch move as in emcee
// (Foreman-Mackey et al. 2013). The walkers are split in two halves; each
// half moves against the other, so its proposals are one residual batch:
//   y_j = x_c + z (x_j - x_c), x_c a random walker of the other half,
//   z ~ g(z) ∝ 1/sqrt(z) on [1/a, a], accepted with min(1, z^(n-1) p(y_j) / p(x_j)).
// The move commutes with any affine map of the parameters, so a narrow
// straight ridge mixes like a round target, with no covariance to adapt.
// R-hat and ESS are computed over the walkers as chains (splitRHat /
// effectiveSampleSize: autocovariances averaged over walkers, emcee's
// recommended estimator; the autocorrelation of the walker-averaged series is
// far noisier at the same length). Walkers are not independent: each move
// uses the other half's positions. With walkers >= 4 n that coupling is weak
// once the ensemble is stationary, and a non-stationary ensemble still shows
// as between-walker variance; the tests check that 4 standard errors from
// this ESS cover known means.
//
// kHamiltonian: Hamiltonian Monte Carlo (Neal 2011) with forward-difference
// gradients of F = 1/2 |r|^2 - log prior (the mode search's linearisation:
// n + 1 simulations per leapfrog step, all chains in one batch). The inverse
// mass matrix is the posterior covariance: the Laplace H^-1 at first, then
// the pooled burn-in draws' covariance (as the adaptive Metropolis); the step
// is steered to an acceptance of 0.8 during burn-in, then frozen. Leapfrog is
// volume-preserving and reversible for any force that depends on position
// only, so a finite-difference gradient leaves the draws exact. Trajectories
// follow a curved ridge (a load traded against the body mass, its position
// and the body's inertia at fixed total mass, CG and roll inertia), where
// straight proposals from one covariance (adaptive Metropolis, ensemble) or
// from the local Gauss-Newton metric (tried: step 0.04) are confined to a
// short chord of it.
#pragma once

#include <Eigen/Dense>
#include <functional>
#include <random>
#include <vector>

#include "pc_ekf/reference/mcmc_reference.h"
#include "pc_ekf/reference/posterior_prior.h"

namespace pc_ekf {

// Log posterior per column (-inf outside the support); one batch per call.
Eigen::VectorXd logPosterior(const PosteriorResidual& residual, const PriorDensity& prior,
                             const Eigen::MatrixXd& xi);
using LogDensityBatch = std::function<Eigen::VectorXd(const Eigen::MatrixXd&)>;

struct SamplerRun {
  std::vector<Eigen::MatrixXd> draws;  // per chain or walker: n x (samples / thin)
  double acceptance = 0.0;             // of the kept iterations
  double scale = 0.0;                  // the stretch a, or the final leapfrog step
};

// Covariance of the pooled later half of the first `iterations` burn-in
// draws (history: one n x burn_in matrix per chain), as both adaptive samplers
// use it. False while fewer than 10 n draws are pooled or it is degenerate.
bool burnInCovariance(const std::vector<Eigen::MatrixXd>& history, int iterations,
                      Eigen::MatrixXd& cov);

// Lower Cholesky factor of a covariance (or metric), with a relative ridge
// when it is numerically singular. Throws std::runtime_error if that fails.
Eigen::MatrixXd choleskyFactor(Eigen::MatrixXd cov);

// walkers: n x chains start positions, logp their (finite) log densities.
// Runs settings.burn_in + settings.samples iterations (each moves every
// walker once) and keeps every settings.thin-th after the burn-in.
SamplerRun runStretchMove(const LogDensityBatch& log_density, Eigen::MatrixXd walkers,
                          Eigen::VectorXd logp, const McmcSettings& settings, std::mt19937_64& rng,
                          const PosteriorProgress& progress);

// chains: n x chains start points inside the support with finite density;
// covariance: the first metric (the Laplace H^-1). Runs settings.burn_in
// (metric and step adapted every settings.adapt_every) + settings.samples
// trajectories per chain, keeping every settings.thin-th.
SamplerRun runHamiltonian(const PosteriorResidual& residual, const PriorDensity& prior,
                          const Eigen::MatrixXd& chains, const Eigen::MatrixXd& covariance,
                          const McmcSettings& settings, std::mt19937_64& rng,
                          const PosteriorProgress& progress);

// kConditionalLaplace: importance sampling from conditional Laplace
// approximations along the ridge (in the spirit of Rue et al.'s 2009
// integrated nested Laplace approximation, made exact by the weights).
//   (a) the k widest directions of the Laplace covariance H^-1 at the mode
//       span the ridge (a), the others cross it (b); k <= 3, by default
//       those with at least 1 % of the widest one's variance;
//   (b) from the mode, each ridge axis is swept both ways until the Laplace
//       marginal of a, exp(-F(a, b*(a))) det(W^T H W)^-1/2 with b*(a) the
//       conditional mode, falls settings.grid_drop below its best;
//   (c) a grid of grid_points^k nodes over that box is solved, each node's
//       Levenberg-Marquardt over b started from a solved neighbour;
//   (d) a draw picks a node by its Laplace mass, a uniformly in its cell, and
//       b from 0.8 N + 0.2 t_3 around the node's mode carried along d b*/d a,
//       with the conditional covariance (W^T H W)^-1;
//   (e) weight = posterior / proposal density (both exact), so the weighted
//       draws are consistent whatever the approximation's error, which only
//       costs efficiency.
// A curved ridge is followed by the conditional modes, not by a straight
// proposal. `chains` independent batches of `samples` draws each (one
// simulation per draw); R-hat compares the batches, each resampled to
// samples / thin draws, and the ESS of each parameter's mean is
// variance / sum w^2 (x - mean)^2 over all draws.
struct ImportanceRun {
  std::vector<Eigen::MatrixXd> draws;  // per batch, resampled: n x (samples / thin)
  Eigen::VectorXd mean, effective_size, r_hat;
  Eigen::MatrixXd covariance;
  double kish = 0.0;            // 1 / sum w^2 over all draws
  double efficiency = 0.0;      // kish / draws
  double largest_weight = 0.0;  // of the normalised weights
  int nodes = 0;                // grid nodes with mass
  int ridge_dimensions = 0;
};
ImportanceRun runConditionalLaplace(const PosteriorResidual& residual, const PriorDensity& prior,
                                    const PosteriorModeEstimate& mode, const McmcSettings& settings,
                                    std::mt19937_64& rng, const PosteriorProgress& progress);

}  // namespace pc_ekf
