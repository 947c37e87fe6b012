// Which uncertain parameters matter for a record: total Sobol indices of each
// parameter on each observed channel, from the PC expansion of the prior
// forecast (the prior propagated over the sample times, no update; no model
// runs beyond that one forecast). Over the record the partial variances are
// summed over the samples before dividing (variance-weighted indices).
#pragma once

#include <Eigen/Dense>
#include <string>
#include <vector>

#include "pc_ekf/filter/pc_propagator.h"

namespace pc_ekf {

struct PriorSensitivity {
  std::vector<std::string> parameters;  // the uncertain parameters, in order
  std::vector<std::string> channels;    // the observed channels
  Eigen::MatrixXd total, first;         // parameters x channels, in [0, 1]
  Eigen::VectorXd variance;             // per channel: prior forecast variance summed over samples
  // Largest total index of parameter i over the channels.
  double largestTotal(int i) const { return total.row(i).maxCoeff(); }
  // Parameters by decreasing largestTotal.
  std::vector<int> ranking() const;
};

// `channels`: indices into the model's channels (the observed ones), `times`
// increasing sample times (> 0).
PriorSensitivity priorSensitivity(const PcPropagator& propagator, const std::vector<double>& times,
                                  const std::vector<int>& channels);

// A ranked text table (one line a parameter: largest total index, then per channel).
std::string sensitivityTable(const PriorSensitivity& s);

}  // namespace pc_ekf
