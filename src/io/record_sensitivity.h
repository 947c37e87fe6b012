// Sensitivity of a config on a record (estimate_offline --sensitivity, the
// node at start) and tolerances_prune: tolerances whose total Sobol index is
// below the threshold on every observed channel are fixed at their nominal.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "pc_ekf/filter/measurement.h"
#include "pc_ekf/sensitivity/prior_sensitivity.h"
#include "pc_ekf/io/estimator_config.h"

namespace pc_ekf {

// Total indices of every uncertain parameter on the config's observed
// channels over `times`: the prior's whole-record simulations at those
// instants (simulated_sensitivity.h; points seeded by collocation.seed).
PriorSensitivity recordSensitivity(const EstimatorConfig& c,
                                   std::shared_ptr<const MechanicalModel> model,
                                   const std::vector<double>& times);
std::vector<double> sampleTimes(const MeasurementSeries& series);

// `c` without the tolerances whose largest total index in `s` is below
// c.tolerances_prune (s: recordSensitivity of c). `pruned` receives one line
// per fixed tolerance, naming its index and the threshold.
EstimatorConfig pruneTolerances(const EstimatorConfig& c, const PriorSensitivity& s,
                                std::vector<std::string>* pruned);

}  // namespace pc_ekf
