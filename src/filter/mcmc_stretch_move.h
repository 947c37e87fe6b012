// The affine-invariant ensemble sampler of runMcmcReference (mcmc_reference.h,
// sampler kEnsemble): Goodman & Weare's (2010) stretch move as in emcee
// (Foreman-Mackey et al. 2013). The walkers are split in two halves; each
// half moves against the other, so its proposals are one residual batch:
//   y_j = x_c + z (x_j - x_c), x_c a random walker of the other half,
//   z ~ g(z) ∝ 1/sqrt(z) on [1/a, a], accepted with min(1, z^(n-1) p(y_j) / p(x_j)).
// The move commutes with any affine map of the parameters, so a narrow
// straight ridge mixes like a round target, with no covariance to adapt.
//
// Diagnostics: R-hat and ESS are computed over the walkers as chains
// (mcmc_reference.h's splitRHat / effectiveSampleSize: autocovariances
// averaged over walkers, emcee's recommended estimator; the autocorrelation of
// the walker-averaged series is far noisier at the same length). Walkers are
// not independent: each move uses the other half's positions. With walkers
// >= 4 n that coupling is weak once the ensemble is stationary, and a
// non-stationary ensemble still shows as between-walker variance; the tests
// check that 4 standard errors from this ESS cover known means.
#pragma once

#include <Eigen/Dense>
#include <functional>
#include <random>
#include <vector>

#include "pc_ekf/filter/mcmc_reference.h"

namespace pc_ekf {

// Log posterior per column (-inf outside the support); one batch per call.
using LogDensityBatch = std::function<Eigen::VectorXd(const Eigen::MatrixXd&)>;

struct StretchMoveRun {
  std::vector<Eigen::MatrixXd> draws;  // per walker: n x (samples / thin)
  double acceptance = 0.0;             // of the kept iterations
};

// walkers: n x chains start positions, logp their (finite) log densities.
// Runs settings.burn_in + settings.samples iterations (each moves every
// walker once) and keeps every settings.thin-th after the burn-in.
StretchMoveRun runStretchMove(const LogDensityBatch& log_density, Eigen::MatrixXd walkers,
                              Eigen::VectorXd logp, const McmcSettings& settings,
                              std::mt19937_64& rng, const PosteriorProgress& progress);

}  // namespace pc_ekf
