// Synthetic measurements from the truth model (SPEC §1.6): simulate at the
// truth parameters, sample at t_k, add seeded Gaussian noise with standard
// deviation sqrt((relative * z_true)^2 + floor^2).
#pragma once

#include <cstdint>
#include <vector>

#include "filter/measurement.h"
#include "model/integrator.h"
#include "model/mechanical_model.h"

namespace pc_ekf {

struct SyntheticDataSettings {
  std::vector<double> times;
  std::vector<int> channels;  // ascending indices into the model's channels
  double noise_relative = 0.01;
  double noise_floor = 0.0;
  std::uint64_t seed = 1;
  IntegratorSettings integration;
};

// `truth_params`: the model's full parameter vector. Also returns the
// noise-free values when `clean` is given.
MeasurementSeries synthesizeMeasurements(const MechanicalModel& model,
                                         const Eigen::VectorXd& truth_params,
                                         const SyntheticDataSettings& settings,
                                         MeasurementSeries* clean = nullptr);

// t_k = k * duration / samples, k = 1..samples.
std::vector<double> uniformSampleTimes(int samples, double duration);

}  // namespace pc_ekf
