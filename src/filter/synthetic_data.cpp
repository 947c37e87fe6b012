#include "filter/synthetic_data.h"

#include <cmath>
#include <random>
#include <stdexcept>

#include "filter/trajectory_simulation.h"

namespace pc_ekf {

MeasurementSeries synthesizeMeasurements(const MechanicalModel& model,
                                         const Eigen::VectorXd& truth_params,
                                         const SyntheticDataSettings& s,
                                         MeasurementSeries* clean) {
  const std::string why = model.invalidReason(truth_params);
  if (!why.empty()) throw std::invalid_argument("truth parameters invalid: " + why);
  const auto channels = simulateChannels(model, truth_params, s.times, s.integration);
  std::mt19937_64 rng(s.seed);
  std::normal_distribution<double> normal;
  MeasurementSeries out;
  if (clean) clean->clear();
  for (std::size_t k = 0; k < s.times.size(); ++k) {
    Measurement m;
    m.time = s.times[k];
    m.channels = s.channels;
    m.values.resize(s.channels.size());
    Measurement exact = m;
    for (std::size_t c = 0; c < s.channels.size(); ++c) {
      const double z = channels[k](s.channels[c], 0);
      const double sd = std::hypot(s.noise_relative * z, s.noise_floor);
      exact.values[c] = z;
      m.values[c] = z + sd * normal(rng);
    }
    out.push_back(m);
    if (clean) clean->push_back(exact);
  }
  return out;
}

std::vector<double> uniformSampleTimes(int samples, double duration) {
  std::vector<double> t(samples);
  for (int k = 1; k <= samples; ++k) t[k - 1] = k * duration / samples;
  return t;
}

}  // namespace pc_ekf
