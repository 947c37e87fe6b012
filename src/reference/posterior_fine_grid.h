// Step 3 of the reference posterior (docs/method.md §4.6): a tensor trapezoid grid along
// the principal axes of a mode's Gauss-Newton Hessian, enlarged until the
// density on its border is negligible. Several modes integrate the union of
// their boxes: a node inside an earlier mode's box belongs to that mode only,
// so overlapping boxes never count mass twice.
#pragma once

#include <Eigen/Dense>
#include <vector>

#include "pc_ekf/reference/posterior_coarse_grid.h"
#include "pc_ekf/reference/posterior_mode_search.h"
#include "pc_ekf/reference/posterior_prior.h"
#include "pc_ekf/filter/posterior_residual.h"
#include "pc_ekf/pc/pc_statistics.h"

namespace pc_ekf {

struct FineGridBox {
  Eigen::VectorXd centre;
  Eigen::MatrixXd axes;         // orthonormal principal axes (columns)
  Eigen::VectorXd half_widths;  // extent along each axis
  bool contains(const Eigen::Ref<const Eigen::VectorXd>& xi) const;
};

struct FineGridSettings {
  int points = 33;                      // per axis
  double span_sigmas = 8.0;             // initial half-width in Gauss-Newton std
  double border_mass_tolerance = 1e-6;  // border mass / mode mass
  double growth = 1.5;                  // span factor per enlargement
  int max_enlargements = 12;
};

struct FineGridIntegral {
  FineGridBox box;
  Eigen::VectorXd spacing;      // node spacing along each axis
  Eigen::MatrixXd nodes;        // dimension x points^dimension
  Eigen::VectorXd log_density;  // unnormalised log posterior; -inf where not counted
  Eigen::VectorXd weights;      // trapezoid weight x cell volume; 0 where not counted
  double log_mass = 0.0;        // log sum(weights * exp(log_density))
  double peak_log_density = 0.0;
  double border_fraction = 0.0;  // density on the border nodes x cell volume / mass
  int enlargements = 0;
  Eigen::VectorXd principal_stddev;  // Gauss-Newton std along the axes
};

// Integrates the posterior around `mode`, skipping nodes outside the support
// and nodes inside any of `earlier`. Residual batches of at most 4096 columns.
FineGridIntegral integrateMode(const PosteriorResidual& residual, const PriorDensity& prior,
                               const PosteriorModeEstimate& mode,
                               const std::vector<FineGridBox>& earlier,
                               const FineGridSettings& settings,
                               const PosteriorProgress& progress = {});

// Mean and covariance of the union of the grids (two passes, shifted by a
// common reference so that the unnormalised densities never overflow).
void posteriorMoments(const std::vector<FineGridIntegral>& grids, Eigen::VectorXd& mean,
                      Eigen::MatrixXd& covariance);

// Marginal density of germ `dimension` as a unit-area histogram (edges in germ
// units). Each node's mass is spread over its cell (sub-sampled), so a rotated
// or axis-aligned grid gives no empty bins; this widens the histogram by the
// cell (variance + spacing^2 / 12), not the moments.
Histogram marginalHistogram(const std::vector<FineGridIntegral>& grids, const PriorDensity& prior,
                            int dimension, int bins);

}  // namespace pc_ekf
