// One-step-at-a-time PC-EKF (SPEC §3.2, §3.3): forecast to each sample's
// time, update with the paper or the square-root rule, report the
// parameters' distribution and health after every sample.
#pragma once

#include <Eigen/Dense>
#include <memory>

#include "filter/health.h"
#include "filter/kalman_update.h"
#include "filter/measurement.h"
#include "filter/pc_propagator.h"

namespace pc_ekf {

struct OneStepSettings {
  UpdateRule rule = UpdateRule::kSquareRoot;
  NoiseModel noise;
  HealthSettings health;
};

struct StepResult {
  int index = 0;  // 1-based sample count since the prior
  double time = 0.0;
  Eigen::VectorXd mean, stddev;  // parameters
  Eigen::MatrixXd coefficients;  // parameters x S
  UpdateDiagnostics update;
  ForecastReport forecast;
  HealthStatus health;
};

class OneStepFilter {
 public:
  OneStepFilter(std::shared_ptr<const PcPropagator> propagator, const OneStepSettings& settings);

  // Throws std::invalid_argument (state untouched) when the sample is before
  // the filter's time, has unknown/duplicate channels or non-finite values.
  StepResult process(const Measurement& m);
  void reset();

  const PcPropagator& propagator() const { return *propagator_; }
  const Eigen::MatrixXd& state() const { return x_; }  // (states + parameters) x S
  double time() const { return t_; }
  int samples() const { return samples_; }
  const OneStepSettings& settings() const { return settings_; }
  // Restores a checkpointed state (same propagator and settings).
  void restore(const Eigen::MatrixXd& x, double time, int samples);

 private:
  std::shared_ptr<const PcPropagator> propagator_;
  OneStepSettings settings_;
  HealthMonitor health_;
  Eigen::MatrixXd x_;
  Eigen::MatrixXd z_coeffs_;  // per-sample buffer
  double t_ = 0.0;
  int samples_ = 0;
};

// Checks a measurement against a model's channels; "" when fine.
std::string measurementProblem(const Measurement& m, int channel_count);

}  // namespace pc_ekf
