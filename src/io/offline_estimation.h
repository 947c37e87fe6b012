// Runs one estimator over a whole measurement record (estimate_offline, the
// reproduction scripts and the tests share this path) and reports the
// The JSON of docs/method.md §8.3, per-sample CSV and final PDFs.
#pragma once

#include <Eigen/Dense>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "pc_ekf/filter/batch_update.h"
#include "pc_ekf/filter/measurement.h"
#include "pc_ekf/filter/pc_propagator.h"
#include "pc_ekf/filter/predictive_check.h"
#include "pc_ekf/filter/prior_sensitivity.h"
#include "pc_ekf/filter/safeguard_rates.h"
#include "pc_ekf/io/estimator_config.h"
#include "pc_ekf/model/mechanical_model.h"
#include "pc_ekf/pc/pc_statistics.h"

namespace pc_ekf {

enum class EstimationMethod { kOneStep, kWholeSet, kEsMda, kEnkf, kGrid };
std::string toString(EstimationMethod m);
EstimationMethod estimationMethodFromString(const std::string& s);  // throws std::invalid_argument

struct SampleRecord {
  int index = 0;  // sample (one_step, enkf) or iteration (es_mda, whole_set)
  double time = 0.0;
  Eigen::VectorXd mean, stddev;
  Eigen::MatrixXd coefficients;  // parameters x S (empty for enkf/grid)
  double nis = 0.0;
  bool nis_window_outside = false;
  bool band_nested = true;
  bool healthy = true;
  Eigen::VectorXd loo_error;  // one-step: per channel (ForecastReport::loo_error)
};

struct ParameterSummary {
  std::string name;
  double mean = 0.0, stddev = 0.0, xi_mean = 0.0, xi_stddev = 0.0;
};

struct CoherenceCheck {
  bool available = false;
  int decimation = 0;
  Eigen::VectorXd disagreement;  // per parameter, combined standard deviations
  double threshold = 3.0;
  bool flagged = false;
};

struct OfflineResult {
  std::string method, update;
  int samples = 0;
  bool healthy = true;
  std::vector<std::string> warnings;
  std::vector<ParameterSummary> parameters;
  std::vector<SampleRecord> records;
  std::vector<std::string> loo_channels;  // one-step: the channels of SampleRecord::loo_error
  std::vector<Histogram> pdfs;  // final, one per parameter (parameter units)
  CoherenceCheck coherence;
  int nis_window_violations = 0;
  PredictiveCheck predictive;   // batch methods, grid and EnKF (health.predictive_check)
  int rejected_samples = 0;     // one-step: gated or rolled back
  int damped_updates = 0;       // updates scaled down by the support rule
  int reopened = 0;             // one-step: times the uncertainty was re-opened
  int relinearized = 0;         // one-step: re-linearisations (filter.relinearize)
  // One-step: the safeguards' rates at the last sample (window and run,
  // docs/method.md §5.9; drive health), and the samples at which a rate's
  // window check was flagged (informational, like nis_window_violations).
  SafeguardRates safeguard_rates;
  int rate_window_violations = 0;
  double band_nested_fraction = 1.0;
  long integrations = 0;  // point- or member-intervals, or full simulations (grid)
  double wall_seconds = 0.0;
  // estimate_offline --sensitivity (empty parameters: not computed), and the
  // tolerances that tolerances_prune fixed ("name: why").
  PriorSensitivity sensitivity;
  std::vector<std::string> pruned_tolerances;
  // Grid posterior only.
  int modes = 0;
  double border_mass = 0.0;
};

// The batch update (whole_set: alphas {1}; es_mda) and its health policy,
// one for estimate_offline and estimator_node's ~estimate_batch: healthy
// when the result is finite and the forecast worked, no support damping was
// needed and the posterior-predictive check (health.predictive_check) holds;
// each failure adds its warning.
struct BatchOutcome {
  BatchResult result;
  bool healthy = true;
  std::vector<std::string> warnings;
  PredictiveCheck predictive;
};
BatchOutcome runBatchEstimate(const EstimatorConfig& c, const PcPropagator& propagator,
                              const MeasurementSeries& series, const std::vector<double>& alphas);

using ProgressCallback = std::function<void(const std::string&)>;

class CoarseGridCache;

// `grid_cache` (grid method only) holds the coarse-grid simulations for the
// record's sample times; they do not depend on the data, so reproductions over
// many seeds build it once per configuration.
OfflineResult runOfflineEstimation(const EstimatorConfig& config, const MeasurementSeries& series,
                                   std::shared_ptr<const MechanicalModel> model,
                                   EstimationMethod method, std::uint64_t seed,
                                   const ProgressCallback& progress = {},
                                   const CoarseGridCache* grid_cache = nullptr);

std::string toJson(const OfflineResult& r);
// samples.csv, pdfs.csv and result.json in `dir` (created). Throws std::runtime_error.
void writeOfflineOutputs(const OfflineResult& r, const std::string& dir);

}  // namespace pc_ekf
