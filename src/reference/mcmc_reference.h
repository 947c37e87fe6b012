// A sampling reference posterior for dimensions the grid of
// reference_posterior.h cannot reach (n = 11: 101^11 coarse nodes). Same
// target: the germs' prior density (PriorDensity) times the Gaussian
// likelihood exp(-1/2 |r|^2) of PosteriorResidual (the filters' R).
//   (1) Levenberg-Marquardt (refineModes) from the given starts: the mode and
//       its Gauss-Newton Hessian H (the Laplace covariance H^-1);
//   (2) `chains` random-walk Metropolis chains, started over-dispersed
//       around the mode (N(mode, spread^2 H^-1), inside the support), all
//       proposing together so that each iteration is one residual batch;
//   (3) during burn-in the proposal covariance is re-estimated from the pooled
//       chains and its scale steered to an acceptance of 0.234 (Haario et
//       al.); after burn-in it is frozen, so the kept draws are an ordinary
//       Metropolis chain of the exact target;
//   (4) per parameter: mean, std, split R-hat and the multi-chain effective
//       sample size (Vehtari et al. 2021, Geyer's initial monotone sequence).
// `sampler` chooses what replaces (2)-(3) (mcmc_samplers.h): kEnsemble, an
// affine-invariant ensemble (Goodman & Weare 2010 stretch move; `chains` are
// its walkers), as fast on a narrow straight ridge as on a round target; or
// kHamiltonian, HMC with finite-difference gradients, whose trajectories
// follow a curved ridge; or kConditionalLaplace, not a chain: independent
// draws from Laplace approximations conditional on a grid along the ridge,
// weighted to the exact posterior. The default stays the adaptive Metropolis, so
// existing callers' draws do not change. On vehicle_live.yaml's n = 15 ridge
// with 1 % noise none of the three chain samplers converges within 10
// minutes; the conditional Laplace does in seconds
// (docs/studies/real_vehicle_reference.md §5).
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <string>
#include <vector>

#include "pc_ekf/reference/posterior_coarse_grid.h"
#include "pc_ekf/reference/posterior_mode_search.h"
#include "pc_ekf/filter/posterior_residual.h"
#include "pc_ekf/filter/uncertain_parameters.h"

namespace pc_ekf {

enum class McmcSampler {
  kAdaptiveMetropolis,  // random-walk chains, covariance adapted during burn-in
  kEnsemble,            // stretch-move walkers; needs chains even and >= 2 n
  kHamiltonian,         // HMC chains, (n + 1) x leapfrog steps simulations per iteration
  kConditionalLaplace,  // importance sampling along the ridge; `chains` are batches
};

struct McmcSettings {
  McmcSampler sampler = McmcSampler::kAdaptiveMetropolis;
  int chains = 8;                    // Metropolis chains, or ensemble walkers
  int burn_in = 2000;                // iterations per chain, adaptation only, discarded
  int samples = 10000;               // kept iterations per chain
  int thin = 1;                      // store every thin-th kept iteration (draws' memory)
  int adapt_every = 50;              // Metropolis and Hamiltonian: burn-in adaptation period
  double stretch = 2.0;              // ensemble only: the stretch move's a (z in [1/a, a])
  double start_spread = 2.0;         // chains start at mode + spread * N(0, H^-1)
  double target_acceptance = 0.234;  // Metropolis only (Hamiltonian: 0.8)
  // kConditionalLaplace only (mcmc_samplers.h): the ridge's dimension k (the
  // Laplace covariance's k widest directions, at most 3; -1: those whose
  // variance is at least 1 % of the widest's), its grid's nodes per axis (0:
  // 41, 21 or 15 for k = 1, 2, 3), and how far (in log density) the grid
  // reaches below the ridge's top.
  int ridge_dimensions = -1;
  int grid_points = 0;
  double grid_drop = 12.0;
  std::uint64_t seed = 1;
  ModeSearchSettings mode_search;
};

struct McmcReference {
  // Germ units.
  Eigen::VectorXd xi_mean, xi_stddev;
  Eigen::MatrixXd xi_covariance;
  Eigen::VectorXd mode_xi, laplace_xi_stddev;  // step (1)
  Eigen::MatrixXd laplace_xi_covariance;       // H^-1
  // Step (1)'s searches that ended at another maximum (not merged into an
  // earlier one) within 50 of the best log density. Random-walk chains do not
  // cross between narrow modes: when this is not 0, the draws describe the
  // best mode's basin only (give more starts, or use the grid posterior).
  int competing_modes = 0;
  double mode_log_density = 0.0;
  // Parameter units (value = nominal (1 + range xi)); equal to the germ units
  // without a ParameterMapping.
  std::vector<std::string> names;
  Eigen::VectorXd mean, stddev;
  Eigen::VectorXd r_hat;           // split R-hat, per parameter (1 = converged)
  Eigen::VectorXd effective_size;  // bulk ESS over all chains, per parameter
  Eigen::VectorXd mean_error;      // Monte Carlo std error of `mean`: stddev / sqrt(ESS)
  double acceptance = 0.0;         // of the kept iterations (importance sampling: its efficiency)
  // kConditionalLaplace: 1 / sum w^2 of the normalised weights, the largest
  // weight, and the ridge grid's nodes with mass (0 for the chain samplers).
  double importance_ess = 0.0;
  double largest_weight = 0.0;
  int ridge_nodes = 0;
  double proposal_scale = 0.0;  // final, relative to 2.38 / sqrt(n) (ensemble: a)
  long simulations = 0;         // forward-model runs of this call
  double seconds = 0.0;
  // chains x (samples / thin) x n, germ units (kept draws). The ensemble's
  // walkers are its chains for R-hat and ESS (see mcmc_samplers.h).
  std::vector<Eigen::MatrixXd> draws;  // one n x (samples / thin) matrix per chain
};

// Split R-hat and bulk ESS of one scalar over chains (rows: chains, columns:
// iterations, at least 4). Exposed for tests.
double splitRHat(const Eigen::MatrixXd& chains);
double effectiveSampleSize(const Eigen::MatrixXd& chains);

// Generic form. `starts`: germ points from which the mode search begins (e.g.
// the prior mean, a few spread points and a filter's estimate); the chains
// start around the best maximum found. Throws
// std::invalid_argument on inconsistent inputs or settings.
McmcReference runMcmcReference(const PosteriorResidual& residual,
                               const std::vector<GermSpec>& prior,
                               const std::vector<Eigen::VectorXd>& starts,
                               const McmcSettings& settings,
                               const PosteriorProgress& progress = {});

// The model's posterior given a measurement series, also in parameter units.
McmcReference runMcmcReference(const MechanicalModel& model, const ParameterMapping& mapping,
                               const MeasurementSeries& series, const NoiseModel& noise,
                               const IntegratorSettings& integration, int threads,
                               const std::vector<Eigen::VectorXd>& starts,
                               const McmcSettings& settings,
                               const PosteriorProgress& progress = {});

}  // namespace pc_ekf
