// The exact Bayesian posterior of the germs given the data (docs/method.md §4.6): prior
// density x Gaussian likelihood of all samples with the filters' R. Its mean
// and std are the truth every filter is judged against.
//   (1) coarse global grid -> local maxima, (2) Levenberg-Marquardt per maximum,
//   (3) fine principal-axis trapezoid grid per mode, enlarged until its border
//   mass is negligible, (4) modes' masses combined (log-sum-exp).
// The pieces live in posterior_{prior,residual,coarse_grid,mode_search,fine_grid}.h.
#pragma once

#include <Eigen/Dense>
#include <string>
#include <vector>

#include "pc_ekf/filter/measurement.h"
#include "pc_ekf/reference/posterior_coarse_grid.h"
#include "pc_ekf/reference/posterior_mode_search.h"
#include "pc_ekf/filter/posterior_residual.h"
#include "pc_ekf/filter/uncertain_parameters.h"
#include "pc_ekf/model/integrator.h"
#include "pc_ekf/model/mechanical_model.h"
#include "pc_ekf/pc/pc_statistics.h"

namespace pc_ekf {

// The grids: the keys of filter.grid (estimator_config.h reads the section
// into this struct).
struct PosteriorGrid {
  int coarse_points = 101;  // per germ, over the prior's range
  int fine_points = 33;     // per principal axis
  double fine_span_sigmas = 8.0;
  double border_mass_tolerance = 1e-6;  // border mass / mode mass
  int threads = 2;
};

struct ReferencePosteriorSettings : PosteriorGrid {
  int bins = 60;  // marginal histograms (pdf.bins)
  // Tuning knobs: how many coarse local maxima are refined (best
  // coarse values first), and how far below the best refined peak a mode may
  // lie (log density) and still get a fine grid. The margin is applied after
  // refinement: with std ~1e-4 the coarse values say little about the peaks.
  int max_candidates = 64;
  double mode_log_margin = 50.0;
  ModeSearchSettings mode_search;
};

struct ReferencePosteriorMode {
  Eigen::VectorXd xi;                // maximiser
  Eigen::VectorXd parameters;        // maximiser in parameter units
  double log_density = 0.0;          // unnormalised log posterior at xi
  double mass_fraction = 0.0;        // of the total posterior mass
  double border_fraction = 0.0;      // border mass / this mode's mass
  Eigen::VectorXd principal_stddev;  // Gauss-Newton std along the grid's axes
  int enlargements = 0;
  bool converged = false;  // Levenberg-Marquardt
};

struct ReferencePosterior {
  Eigen::VectorXd xi_mean, xi_stddev;
  Eigen::MatrixXd xi_covariance;
  // In parameter units (value = nominal (1 + range xi)); equal to the germ
  // units when computed without a ParameterMapping.
  std::vector<std::string> names;
  Eigen::VectorXd mean, stddev;
  std::vector<Histogram> marginals;           // one per parameter, unit area
  std::vector<ReferencePosteriorMode> modes;  // heaviest first

  double border_mass = 0.0;     // total border mass / total mass
  double log_mass = 0.0;        // log of the integral of prior x exp(-1/2 |r|^2)
  long simulations = 0;         // forward-model runs of this call
  long cached_simulations = 0;  // coarse-grid runs taken from a cache instead
  Eigen::Index coarse_grid_size = 0;
  double coarse_best_log_density = 0.0;
  Eigen::VectorXd coarse_best_xi;
  int coarse_local_maxima = 0;
  int refined_candidates = 0;
  double coarse_seconds = 0.0, refine_seconds = 0.0, fine_seconds = 0.0, total_seconds = 0.0;
};

// Generic form. coarse_log_likelihood, when given, holds -1/2 |r|^2 at every
// node of CoarseGrid(prior, settings.coarse_points) and replaces step (1)'s
// evaluations. Throws std::invalid_argument on inconsistent inputs and
// std::runtime_error when the posterior has no mass on the coarse grid.
ReferencePosterior computeReferencePosterior(const PosteriorResidual& residual,
                                             const std::vector<GermSpec>& prior,
                                             const ReferencePosteriorSettings& settings,
                                             const Eigen::VectorXd* coarse_log_likelihood = nullptr,
                                             const PosteriorProgress& progress = {});

// The model's posterior given a measurement series; `cache` (built for the
// same mapping, sample times, integration step and coarse_points) skips the
// coarse simulations. Results also in parameter units via the mapping.
ReferencePosterior computeReferencePosterior(
    const MechanicalModel& model, const ParameterMapping& mapping, const MeasurementSeries& series,
    const NoiseModel& noise, const IntegratorSettings& integration,
    const ReferencePosteriorSettings& settings, const CoarseGridCache* cache = nullptr,
    const PosteriorProgress& progress = {});

}  // namespace pc_ekf
