// Calibration of the vehicle on records with a known load (calibrate_vehicle,
// docs/real_vehicle.md): the tolerances are estimated, and their posterior
// becomes the tolerances of the vehicle file that later runs merge in.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "pc_ekf/filter/measurement.h"
#include "pc_ekf/io/offline_estimation.h"
#include "pc_ekf/io/vehicle_file.h"

namespace pc_ekf {

struct CalibrationRecord {
  EstimatorConfig config;  // the load in vehicle:, the values to calibrate in tolerances:
  MeasurementSeries series;
  std::shared_ptr<const MechanicalModel> model;
  std::string label;  // e.g. the bag's path, for the file's header
};

struct CalibrationResult {
  std::vector<OfflineResult> runs;  // one per record, in order
  bool healthy = true;              // every run healthy
  // The last run's posterior of the tolerances, moment-matched (same germs):
  // this prior has that posterior's mean and std.
  std::vector<UncertainParameter> tolerances;
};

// ConfigError when a record's config has no tolerances, lists the load under
// uncertain:, or names other tolerances than the first record's.
void checkCalibrationConfig(const EstimatorConfig& c, const EstimatorConfig* first = nullptr);

// Runs the records one after another: each record's tolerances start from the
// previous record's moment-matched posterior (sequential Bayes; correlations
// between the vehicle values are not carried from one record to the next).
CalibrationResult calibrate(std::vector<CalibrationRecord> records, EstimationMethod method,
                            std::uint64_t seed, const ProgressCallback& progress = {});

// The config's tolerances replaced by `tolerances` (same names).
EstimatorConfig withTolerances(EstimatorConfig c, const std::vector<UncertainParameter>& tolerances);

// The vehicle file of a calibration: every value of the model (calibrated
// means, the rest as in `vehicle_keys`/the model), the remaining tolerances.
// `vehicle_keys`: the config's vehicle: section as (key, text), for the laws
// that are no parameter (e.g. the damper law).
VehicleFile calibratedVehicleFile(const CalibrationResult& result, const EstimatorConfig& last,
                                  const std::vector<std::pair<std::string, std::string>>& vehicle_keys,
                                  const std::vector<std::string>& header);

}  // namespace pc_ekf
