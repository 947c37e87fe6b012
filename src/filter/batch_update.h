// Whole-set-of-data-at-once update (docs/method.md §4.4, paper eq. 33-37) and its
// iterated form ES-MDA (Emerick & Reynolds 2013): forecast every collocation
// point over the whole record from t = 0 with the current parameter
// expansion, stack all observations, update the parameter coefficients.
// Cost is linear in the number of observations (see kalman_update.h).
#pragma once

#include <Eigen/Dense>
#include <vector>

#include "pc_ekf/filter/batch_nuisance.h"
#include "pc_ekf/filter/kalman_update.h"
#include "pc_ekf/filter/measurement.h"
#include "pc_ekf/filter/pc_propagator.h"
#include "pc_ekf/filter/update_safeguards.h"

namespace pc_ekf {

struct BatchResult {
  Eigen::MatrixXd coefficients;  // parameters x S after the last iteration
  Eigen::VectorXd mean, stddev;
  int iterations = 0;
  int observations = 0;        // stacked scalar observations
  double nis = 0.0;            // of the first iteration (prior predictive)
  bool finite = true;
  ForecastReport forecast;     // merged over iterations
  double damping = 1.0;        // smallest fraction of an iteration's update applied (support rule)
  // BatchRestarts::local_covariance: whether the covariance is localCovariance's
  // (false when it was asked for and a run or a factorisation failed: the passes' stays).
  bool local_covariance = false;
  // With local_covariance: the posterior's mode near the mean (posteriorMode),
  // where the posterior-predictive check runs; empty otherwise.
  Eigen::VectorXd mode;
};

// Stacked observation coefficients (observations x S) of the parameter
// expansion theta_coeffs over the record, the stacked data and R's diagonal;
// a sample with noise correlated between its channels whitened
// (NoiseWhitening: its rows and data by L^-1, its variances 1).
struct StackedObservations {
  Eigen::MatrixXd z_coeffs;
  Eigen::VectorXd z;
  Eigen::VectorXd variances;
};
// With nuisance values (nuisance_u: nuisanceSensitivity's columns, raw units;
// nuisance_std their prior stds) the rows and data are whitened for them too
// (NuisanceWhitening), so that R stays the sensors' own.
StackedObservations forecastRecord(const PcPropagator& propagator,
                                   const Eigen::MatrixXd& theta_coeffs,
                                   const MeasurementSeries& series, const NoiseModel& noise,
                                   ForecastReport* report,
                                   const Eigen::MatrixXd* nuisance_u = nullptr,
                                   const Eigen::VectorXd* nuisance_std = nullptr);

// alphas = {1} is the paper's single whole-set update; ES-MDA uses
// sum(1/alpha_i) = 1 (default four times 4). R_i = alpha_i R.
// start: the parameter coefficients to begin from (parameters x S); empty:
// the propagator's prior. nuisance: marginalised in every pass, their
// sensitivity taken at that pass's mean (batch_nuisance.h).
BatchResult batchUpdate(const PcPropagator& propagator, const MeasurementSeries& series,
                        const NoiseModel& noise, UpdateRule rule,
                        const std::vector<double>& alphas,
                        SupportRule support = SupportRule::kIgnore,
                        const Eigen::MatrixXd& start = Eigen::MatrixXd(),
                        const BatchNuisance& nuisance = BatchNuisance());

// Re-linearised batch update (docs/method.md §4.5): after the update from the
// prior, `restarts` times again from a working prior around the last result
// (std = width x its std, for the parameters that narrowed below their prior
// std / width; the others keep the prior), each result reported with the
// working prior's information replaced by the prior's (prior_correction.h).
// The first update's surrogate spans the prior's whole width, where the
// readings are far from linear in the parameters; the restarts' surrogates
// span the posterior's neighbourhood. restarts = 0: batchUpdate.
struct BatchRestarts {
  // The rule (filter.es_mda.width): width > kMinWidth, so that a restart widens.
  static constexpr double kMinWidth = 1.0;
  int restarts = 0;  // >= 0
  double width = 2.0;
  // filter.es_mda.covariance: local: the final result's covariance from the
  // model's local information at its mean (local_covariance.h), its mean the
  // passes'. false (passes): the passes' own.
  bool local_covariance = false;
  // The road's cross-fall and the IMU's biases, marginalised in every pass
  // (filter.horizon.cross_fall, accel_bias, gyro_bias; batch_nuisance.h).
  BatchNuisance nuisance;
};
BatchResult batchUpdateRestarted(const PcPropagator& propagator, const MeasurementSeries& series,
                                 const NoiseModel& noise, UpdateRule rule,
                                 const std::vector<double>& alphas, SupportRule support,
                                 const BatchRestarts& restarts);

// ES-MDA: the keys of filter.es_mda (estimator_config.h reads the section
// into this struct): the passes' inflation factors and the restarts.
struct EsMdaSettings : BatchRestarts {
  std::vector<double> alphas{4.0, 4.0, 4.0, 4.0};  // sum of 1/alpha must be 1
};

}  // namespace pc_ekf
