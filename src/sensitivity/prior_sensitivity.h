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
  Eigen::VectorXd variance;             // per channel: the prior's variance summed over samples
  // Per channel: the share of the forecast's variance that the truncated
  // expansion misses, estimated by the projection's leave-one-out error e_k
  // at each sample (sum_k e_k^2 var_k / sum_k var_k; e_k as
  // CollocationDesign::leaveOneOutError). The indices above are fractions of
  // the expansion's variance: a missed share of 0.2 leaves every index up to
  // that much low. Empty when the design has no leave-one-out error.
  Eigen::VectorXd unexplained;
  // How the indices were computed (simulated_sensitivity.h: the basis chosen,
  // its points) and the model runs it took; empty and 0 for priorSensitivity.
  std::string expansion;
  long simulations = 0;
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
