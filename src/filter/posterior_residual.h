// Whitened residuals of the reference posterior (docs/method.md §4.6): the likelihood is
// exp(-1/2 |r(xi)|^2), r = (z - h(xi)) / sqrt(R) stacked over samples and
// observed channels, R from NoiseModel::variances (the filters' R, docs/method.md §1.6).
// Behind an interface so the posterior machinery can be tested on synthetic
// likelihoods with known answers.
#pragma once

#include <Eigen/Dense>
#include <atomic>
#include <vector>

#include "pc_ekf/filter/measurement.h"
#include "pc_ekf/filter/uncertain_parameters.h"
#include "pc_ekf/model/integrator.h"
#include "pc_ekf/model/mechanical_model.h"

namespace pc_ekf {

class PosteriorResidual {
 public:
  virtual ~PosteriorResidual() = default;
  virtual int dimension() const = 0;
  // xi: dimension() x B germ points. Returns residual length x B; a column with
  // a non-finite entry has zero likelihood. Called with large batches: an
  // implementation should evaluate all columns at once (threads, SIMD).
  virtual Eigen::MatrixXd residuals(const Eigen::MatrixXd& xi) const = 0;
  // Forward-model runs so far (0 for synthetic residuals).
  virtual long simulations() const { return 0; }
};

// -1/2 |r|^2 per column, -inf where a column is not finite.
Eigen::VectorXd logLikelihood(const Eigen::MatrixXd& residuals);

// channels[k]: all model channels x B at series[k].time. Returns the observed
// channels' whitened residuals stacked sample by sample (length = number of
// observed values in the series).
Eigen::MatrixXd whitenedResiduals(const MeasurementSeries& series, const NoiseModel& noise,
                                  const std::vector<Eigen::MatrixXd>& channels);

// Simulates the germ points xi (count x B) through `times` (docs/method.md §1.6 channels);
// columns whose parameters are inadmissible stay NaN and are not simulated.
// Adds the number of simulated columns to *simulations when given.
std::vector<Eigen::MatrixXd> simulateGermChannels(const MechanicalModel& model,
                                                  const ParameterMapping& mapping,
                                                  const Eigen::MatrixXd& xi,
                                                  const std::vector<double>& times,
                                                  const IntegratorSettings& integration,
                                                  int threads, long* simulations = nullptr);

// The vehicle (or any MechanicalModel) likelihood. Keeps references to model
// and mapping: they must outlive it.
class ModelPosteriorResidual : public PosteriorResidual {
 public:
  // Throws std::invalid_argument on an empty series or non-finite values.
  ModelPosteriorResidual(const MechanicalModel& model, const ParameterMapping& mapping,
                         MeasurementSeries series, const NoiseModel& noise,
                         const IntegratorSettings& integration, int threads);

  int dimension() const override { return mapping_.count(); }
  Eigen::MatrixXd residuals(const Eigen::MatrixXd& xi) const override;
  long simulations() const override { return simulations_.load(); }

  const MeasurementSeries& series() const { return series_; }
  const NoiseModel& noise() const { return noise_; }
  const std::vector<double>& times() const { return times_; }

 private:
  const MechanicalModel& model_;
  const ParameterMapping& mapping_;
  MeasurementSeries series_;
  NoiseModel noise_;
  IntegratorSettings integration_;
  int threads_;
  std::vector<double> times_;
  mutable std::atomic<long> simulations_{0};
};

}  // namespace pc_ekf
