// Monte-Carlo ensemble Kalman filter with perturbed observations (docs/method.md §4.7):
// the cost/accuracy baseline for the PC-EKF, on the same model and data.
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <memory>
#include <random>

#include "pc_ekf/filter/measurement.h"
#include "pc_ekf/filter/uncertain_parameters.h"
#include "pc_ekf/model/integrator.h"
#include "pc_ekf/model/mechanical_model.h"

namespace pc_ekf {

// The ensemble: the keys of filter.enkf (estimator_config.h reads the
// section into this struct).
struct EnkfEnsemble {
  static constexpr int kMinMembers = 2;  // the filter's rule (filter.enkf.members)
  int members = 200;
  std::uint64_t seed = 7;
  // false: perturbed observations (docs/method.md §4.7, the baseline). true: the serial
  // square-root rule of docs/method.md §4.3 on the ensemble (an EAKF), which isolates
  // the effect of observation perturbations when comparing with the PC-EKF.
  bool square_root = false;
};

// The ensemble, and what the filter shares with the other methods: R, the
// integrator and the threads (makeEnkfSettings, estimation_setup.h).
struct EnkfSettings : EnkfEnsemble {
  NoiseModel noise;
  IntegratorSettings integration;
  int threads = 2;
};

struct EnkfStep {
  int index = 0;
  double time = 0.0;
  Eigen::VectorXd mean, stddev;  // parameters
  Eigen::VectorXd innovation;
  double nis = 0.0;
  int inadmissible_members = 0;  // frozen: parameters outside the model's domain
  bool finite = true;
};

class EnsembleKalmanFilter {
 public:
  EnsembleKalmanFilter(std::shared_ptr<const MechanicalModel> model, ParameterMapping mapping,
                       const EnkfSettings& settings);
  // Throws std::invalid_argument for a bad measurement or a time before the filter's.
  EnkfStep process(const Measurement& m);

  const Eigen::MatrixXd& parameters() const { return theta_; }  // parameters x members
  long integrations() const { return integrations_; }          // member-intervals

 private:
  void forecast(double t1, int* inadmissible);

  std::shared_ptr<const MechanicalModel> model_;
  ParameterMapping mapping_;
  EnkfSettings settings_;
  std::mt19937_64 rng_;
  Eigen::MatrixXd theta_;   // parameters x members
  Eigen::ArrayXXd states_;  // states x members
  std::vector<bool> admissible_;
  double t_ = 0.0;
  int samples_ = 0;
  long integrations_ = 0;
};

}  // namespace pc_ekf
