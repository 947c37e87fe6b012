#include "pc_ekf/io/record_sensitivity.h"

#include <cstdio>

#include "pc_ekf/sensitivity/simulated_sensitivity.h"
#include "pc_ekf/io/estimation_setup.h"

namespace pc_ekf {

std::vector<double> sampleTimes(const MeasurementSeries& series) {
  std::vector<double> t;
  for (const auto& m : series) {
    if (t.empty() || m.time > t.back()) t.push_back(m.time);
  }
  return t;
}

PriorSensitivity recordSensitivity(const EstimatorConfig& c,
                                   std::shared_ptr<const MechanicalModel> model,
                                   const std::vector<double>& times) {
  // Whole-record simulations of the prior (simulated_sensitivity.h), not
  // the filters' re-projected forecast.
  const ParameterMapping mapping(*model, c.uncertain);
  SimulatedSensitivitySettings settings;
  settings.seed = c.collocation.seed;
  settings.threads = c.collocation.threads;
  return simulatedSensitivity(*model, mapping, times, channelIndices(c), c.integration, settings);
}

EstimatorConfig pruneTolerances(const EstimatorConfig& c, const PriorSensitivity& s,
                                std::vector<std::string>* pruned) {
  EstimatorConfig out = c;
  if (!(c.tolerances_prune > 0.0)) return out;
  out.uncertain.resize(c.loadCount());
  out.tolerance_count = 0;
  std::vector<double> drift, standing;
  for (int i = 0; i < static_cast<int>(c.uncertain.size()); ++i) {
    const bool tolerance = i >= c.loadCount();
    if (tolerance && s.largestTotal(i) < c.tolerances_prune) {
      char line[200];
      std::snprintf(line, sizeof(line),
                    "%s fixed at %.6g: largest total Sobol index %.2e below tolerances_prune %.2e",
                    c.uncertain[i].name.c_str(), c.uncertain[i].nominal, s.largestTotal(i),
                    c.tolerances_prune);
      if (pruned) pruned->push_back(line);
      continue;
    }
    if (tolerance) {
      out.uncertain.push_back(c.uncertain[i]);
      ++out.tolerance_count;
    }
    if (c.safeguards.drift.size() != 0) drift.push_back(c.safeguards.drift[i]);
    if (c.safeguards.drift_standing.size() != 0) standing.push_back(c.safeguards.drift_standing[i]);
  }
  out.safeguards.drift = Eigen::Map<const Eigen::VectorXd>(
      drift.data(), static_cast<Eigen::Index>(drift.size()));
  out.safeguards.drift_standing = Eigen::Map<const Eigen::VectorXd>(
      standing.data(), static_cast<Eigen::Index>(standing.size()));
  // truth.xi and the schedule follow the parameters they belong to.
  std::vector<bool> kept(c.uncertain.size(), false);
  for (std::size_t i = 0, k = 0; i < c.uncertain.size() && k < out.uncertain.size(); ++i) {
    if (c.uncertain[i].name == out.uncertain[k].name) kept[i] = true, ++k;
  }
  const auto keep = [&kept](const std::vector<double>& xi) {
    std::vector<double> r;
    for (std::size_t i = 0; i < xi.size() && i < kept.size(); ++i) {
      if (kept[i]) r.push_back(xi[i]);
    }
    return r;
  };
  out.truth.xi = keep(c.truth.xi);
  for (auto& change : out.truth.schedule) change.xi = keep(change.xi);
  return out;
}

}  // namespace pc_ekf
