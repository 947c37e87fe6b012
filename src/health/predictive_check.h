// Posterior-predictive check of a batch estimate (whole-set, ES-MDA, grid,
// EnKF): simulate the model at the posterior mean and compare the whole
// record with it. If the data are consistent with the model and R, the
// normalised residual sum of squares
//   T = sum_k sum_c (z_kc - h_c(t_k; theta_mean))^2 / R_kc
// is chi-square distributed with (observed entries - parameters) degrees of
// freedom (the parameters were fitted to the same data), its spread widened
// by noise that neighbouring samples share (road-free inputs); T outside the
// two-sided bounds flags model error (or an R that does not describe the
// sensor), naming the channels and the time window that contribute most.
#pragma once

#include <Eigen/Dense>
#include <string>
#include <vector>

#include "pc_ekf/filter/batch_nuisance.h"
#include "pc_ekf/filter/measurement.h"
#include "pc_ekf/model/integrator.h"
#include "pc_ekf/model/mechanical_model.h"

namespace pc_ekf {

struct PredictiveCheck {
  bool available = false;  // false: no data, or the mean is outside the model's domain
  double statistic = 0.0;  // T
  int dof = 0;
  double lower = 0.0, upper = 0.0;
  // T's variance over the chi-square's 2 dof (1: independent samples); the
  // bounds are those of spread * chi2(dof / spread), the same mean.
  double spread = 1.0;
  bool outside = false;        // drives health
  Eigen::VectorXd channel_mean;  // per model channel: mean of the normalised squared residuals
  std::vector<std::string> channel_names;  // the model channels with entries, by name
  std::vector<double> observed_mean;        // their channel_mean, in that order
  int worst_window_begin = 0, worst_window_end = 0;  // sample indices [begin, end)
  double worst_window_mean = 0.0;
  std::string problem;  // why unavailable
  // "posterior-predictive check: ..." naming channels and window; "" when inside.
  std::string warning(const std::vector<std::string>& channel_names,
                      const MeasurementSeries& series) const;
};

// `params`: the model's full parameter vector at the posterior mean;
// `fitted`: number of estimated parameters (subtracted from the dof).
// `nuisance`: the batch methods' marginalised cross-fall and biases
// (batch_nuisance.h): the residuals are whitened for them too.
PredictiveCheck posteriorPredictiveCheck(const MechanicalModel& model,
                                         const Eigen::VectorXd& params,
                                         const MeasurementSeries& series, const NoiseModel& noise,
                                         const IntegratorSettings& integration, int fitted,
                                         double confidence,
                                         const BatchNuisance& nuisance = BatchNuisance());

}  // namespace pc_ekf
