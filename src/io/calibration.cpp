#include "pc_ekf/io/calibration.h"

#include <set>
#include <stdexcept>

#include "pc_ekf/io/tolerances.h"

namespace pc_ekf {

void checkCalibrationConfig(const EstimatorConfig& c, const EstimatorConfig* first) {
  if (c.loadCount() > 0) {
    throw ConfigError(c.source + ": key 'uncertain': calibration needs a known load: set it in " +
                      "vehicle: (added_mass, added_mass_position) and list no uncertain: entry (" +
                      c.uncertain.front().name + " is listed)");
  }
  if (c.tolerance_count == 0) {
    throw ConfigError(c.source + ": key 'tolerances': nothing to calibrate: list the vehicle " +
                      "values to calibrate under tolerances:");
  }
  if (!first) return;
  std::set<std::string> a, b;
  for (const auto& u : first->uncertain) a.insert(u.name);
  for (const auto& u : c.uncertain) b.insert(u.name);
  if (a != b) {
    throw ConfigError(c.source + ": key 'tolerances': every calibration record must calibrate the " +
                      "same values as the first (" + first->source + ")");
  }
}

EstimatorConfig withTolerances(EstimatorConfig c, const std::vector<UncertainParameter>& tolerances) {
  for (auto& u : c.uncertain) {
    for (const auto& t : tolerances) {
      if (t.name == u.name) u = t;
    }
  }
  return c;
}

CalibrationResult calibrate(std::vector<CalibrationRecord> records, EstimationMethod method,
                            std::uint64_t seed, const ProgressCallback& progress) {
  if (records.empty()) throw std::invalid_argument("calibrate: no record");
  CalibrationResult out;
  for (std::size_t k = 0; k < records.size(); ++k) {
    CalibrationRecord& r = records[k];
    checkCalibrationConfig(r.config, &records.front().config);
    if (k > 0) r.config = withTolerances(r.config, out.tolerances);
    if (progress) progress("calibration record " + std::to_string(k + 1) + " of " +
                           std::to_string(records.size()) + ": " + r.label);
    OfflineResult run = runOfflineEstimation(r.config, r.series, r.model, method, seed, progress);
    out.healthy = out.healthy && run.healthy;
    out.tolerances.clear();
    for (std::size_t i = 0; i < r.config.uncertain.size(); ++i) {
      const UncertainParameter& u = r.config.uncertain[i];
      const ParameterSummary& p = run.parameters.at(i);
      out.tolerances.push_back(momentMatched(u.name, p.mean, p.stddev, u.germ));
    }
    out.runs.push_back(std::move(run));
  }
  return out;
}

VehicleFile calibratedVehicleFile(const CalibrationResult& result, const EstimatorConfig& last,
                                  const std::vector<std::pair<std::string, std::string>>& vehicle_keys,
                                  const std::vector<std::string>& header) {
  VehicleFile f;
  f.header = header;
  const auto& names = last.model_type->parameterNames();
  const std::shared_ptr<const ModelParameters> given = last.modelParameters();
  const Eigen::VectorXd& values = given->values;
  std::set<std::string> parameters(names.begin(), names.end());
  const OfflineResult& run = result.runs.back();
  for (std::size_t i = 0; i < names.size(); ++i) {
    double v = values[static_cast<Eigen::Index>(i)];
    for (const auto& p : run.parameters) {
      if (p.name == names[i]) v = p.mean;
    }
    f.vehicle.emplace_back(names[i], roundTripText(v));
  }
  for (const auto& kv : vehicle_keys) {
    if (!parameters.count(kv.first)) f.vehicle.push_back(kv);  // laws: as given
  }
  f.tolerances = result.tolerances;
  return f;
}

}  // namespace pc_ekf
