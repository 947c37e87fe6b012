// Step 1 of the reference posterior (docs/method.md §4.6): a global tensor grid over the
// prior's range, and a cache of the model's channels on it. The simulations do
// not depend on the data, only on the model, the mapping and the sample times,
// so one cache serves every noise draw (reproduction over many seeds).
#pragma once

#include <Eigen/Dense>
#include <functional>
#include <string>
#include <vector>

#include "pc_ekf/filter/measurement.h"
#include "pc_ekf/reference/posterior_prior.h"
#include "pc_ekf/filter/uncertain_parameters.h"
#include "pc_ekf/model/integrator.h"
#include "pc_ekf/model/mechanical_model.h"

namespace pc_ekf {

using PosteriorProgress = std::function<void(const std::string&)>;

// points_per_axis equally spaced nodes per germ over PriorDensity::gridRange,
// ends included; nodes() is dimension x size, first germ varying fastest.
class CoarseGrid {
 public:
  static constexpr int kMinPoints = 3;  // the rule (grid.coarse_points)
  // Throws std::invalid_argument when points_per_axis < kMinPoints.
  CoarseGrid(const PriorDensity& prior, int points_per_axis);

  int dimension() const { return static_cast<int>(nodes_.rows()); }
  int pointsPerAxis() const { return points_; }
  Eigen::Index size() const { return nodes_.cols(); }
  const Eigen::MatrixXd& nodes() const { return nodes_; }
  // Log prior density at every node (-inf outside the support).
  const Eigen::VectorXd& logPrior() const { return log_prior_; }

  // Nodes whose finite value is >= every neighbour's (3^n - 1 neighbours),
  // sorted by value, best first.
  std::vector<Eigen::Index> localMaxima(const Eigen::VectorXd& values) const;

 private:
  int points_;
  Eigen::MatrixXd nodes_;
  Eigen::VectorXd log_prior_;
};

class CoarseGridCache {
 public:
  // Simulates every node of positive prior density through `times`, in
  // batches over `threads` threads. Keeps no reference to model or mapping.
  CoarseGridCache(const MechanicalModel& model, const ParameterMapping& mapping,
                  std::vector<double> times, const IntegratorSettings& integration,
                  int coarse_points, int threads, const PosteriorProgress& progress = {});

  const CoarseGrid& grid() const { return grid_; }
  const std::vector<double>& times() const { return times_; }
  // channels()[k]: all channels x grid().size() at times()[k]; NaN where the
  // node was not simulated (zero prior density or inadmissible parameters).
  const std::vector<Eigen::MatrixXd>& channels() const { return channels_; }
  long simulations() const { return simulations_; }

  // Throws std::invalid_argument naming the first difference when the cache
  // was not built for these germs, parameters, times, step or grid size.
  void checkCompatible(const ParameterMapping& mapping, const std::vector<double>& times,
                       const IntegratorSettings& integration, int coarse_points) const;
  // Log-likelihood (-1/2 |r|^2) at every node for a data set sampled at times().
  Eigen::VectorXd logLikelihood(const MeasurementSeries& series, const NoiseModel& noise) const;

 private:
  std::vector<UncertainParameter> uncertain_;
  std::vector<double> times_;
  IntegratorSettings integration_;
  CoarseGrid grid_;
  std::vector<Eigen::MatrixXd> channels_;
  long simulations_ = 0;
};

}  // namespace pc_ekf
