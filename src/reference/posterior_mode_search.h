// Step 2 of the reference posterior (docs/method.md §4.6): Levenberg-Marquardt on the
// negative log posterior F = 1/2 |r|^2 - log prior, started from the coarse
// grid's local maxima. All starts iterate together so that every residual
// evaluation (trial points and finite-difference stencils) is one batch.
#pragma once

#include <Eigen/Dense>
#include <limits>
#include <vector>

#include "pc_ekf/reference/posterior_prior.h"
#include "pc_ekf/filter/posterior_residual.h"

namespace pc_ekf {

struct ModeSearchSettings {
  int max_iterations = 100;
  // Forward-difference step, relative to each germ's grid range width. The
  // posterior std is >= ~1e-5 of the range and the residuals are smooth in xi
  // (fixed integration steps), so 1e-7 keeps both truncation and round-off small.
  double difference_step = 1e-7;
  // Converged when an accepted step lowers F by less than this * (1 + |F|).
  double relative_decrease = 1e-12;
  // A search within this many Gauss-Newton std of a better one stops as its
  // duplicate (same basin); distinct modes closer than this share a fine grid.
  double merge_distance = 3.0;
};

struct PosteriorModeEstimate {
  Eigen::VectorXd xi;
  double log_density = 0.0;  // log prior + log likelihood (unnormalised) at xi
  // Gauss-Newton Hessian of F at xi: J^T J + the prior's curvature.
  Eigen::MatrixXd hessian;
  int iterations = 0;
  bool converged = false;
  int duplicate_of = -1;  // index of the start it merged into, or -1
};

// A point's whitened residual r and forward-difference Jacobian J (steps
// `relative` x each germ's grid range, pointing into the support), and
// F = 1/2 |r|^2 - log prior there (+inf outside the support or where r is not
// finite). Shared by the mode search and the Hamiltonian sampler
// (mcmc_samplers.h); all points and stencils are one residual batch.
struct Linearisation {
  Eigen::VectorXd x;
  Eigen::VectorXd r;
  Eigen::MatrixXd jacobian;
  double f = std::numeric_limits<double>::infinity();
};
std::vector<Linearisation> linearise(const PosteriorResidual& residual, const PriorDensity& prior,
                                     const std::vector<Eigen::VectorXd>& points, double relative);

// Gauss-Newton Hessian of F, J^T J + the prior's curvature; *gradient = dF/dxi
// when given.
Eigen::MatrixXd gaussNewtonHessian(const PriorDensity& prior, const Linearisation& l,
                                   Eigen::VectorXd* gradient);

// One estimate per start (same order); starts must have finite log posterior.
// Steps are projected onto the prior's support.
std::vector<PosteriorModeEstimate> refineModes(const PosteriorResidual& residual,
                                               const PriorDensity& prior,
                                               const std::vector<Eigen::VectorXd>& starts,
                                               const ModeSearchSettings& settings);

}  // namespace pc_ekf
