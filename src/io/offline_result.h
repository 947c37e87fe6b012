// What an offline run reports (runOfflineEstimation, runRoadFreeOneStep):
// the summary behind the JSON of docs/method.md §8.3, and the per-sample
// records, which go to a sink as they are made instead of being kept.
#pragma once

#include <Eigen/Dense>
#include <limits>
#include <string>
#include <vector>

#include "pc_ekf/health/predictive_check.h"
#include "pc_ekf/sensitivity/prior_sensitivity.h"
#include "pc_ekf/filter/safeguard_rates.h"
#include "pc_ekf/filter/update_safeguards.h"
#include "pc_ekf/pc/pc_statistics.h"

namespace pc_ekf {

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
  // One-step with a model that gives it (MechanicalModel::hasLoadTransferRatio):
  // the load transfer ratio at this sample, at the posterior mean; NaN otherwise.
  double load_transfer_ratio = std::numeric_limits<double>::quiet_NaN();
};

// The per-sample rows' columns besides the records' own: the parameters'
// names and the leave-one-out channels (one-step; SampleRecord::loo_error).
struct SampleColumns {
  std::vector<std::string> parameters, loo_channels;
  bool load_transfer_ratio = false;  // a last column load_transfer_ratio
};

// Takes the run's per-sample records as they are made (estimate_offline
// --out: samples.csv), so that memory does not grow with the record.
class SampleSink {
 public:
  virtual ~SampleSink() = default;
  virtual void begin(const SampleColumns& columns) = 0;  // once, before the first record
  // By value: a record handed over (an rvalue) is moved, not copied.
  virtual void add(SampleRecord record) = 0;
};

struct ParameterSummary {
  std::string name;
  double mean = 0.0, stddev = 0.0, xi_mean = 0.0, xi_stddev = 0.0;
};

// A quantity derived from the parameters (the rollover outputs,
// filter/rollover_quantities.h): its PC expansion, mean, std and PDF.
struct DerivedSummary {
  std::string name;
  double mean = 0.0, stddev = 0.0;
  Eigen::VectorXd coefficients;  // S terms
  Histogram pdf;                 // parameter units; empty when not drawn
};

struct CoherenceCheck {
  bool available = false;
  int decimation = 0;
  Eigen::VectorXd disagreement;  // per parameter, combined standard deviations
  double threshold = 3.0;
  bool flagged = false;
};

// A load change found by the one-step filter (filter.reopen.mode load): the
// time of its first sample, of the sample that found it, and the load's
// parameters right after (mean, stddev).
struct LoadChangeEvent {
  double began = 0.0, found = 0.0;
  std::vector<ParameterSummary> load;
};

struct OfflineResult {
  std::string method, update;
  int samples = 0;
  bool healthy = true;
  std::vector<std::string> warnings;
  std::vector<ParameterSummary> parameters;
  // The last record the sink was given (the final estimate; every record
  // went to the sink, none is kept).
  SampleRecord last_record;
  std::vector<std::string> loo_channels;  // one-step: the channels of SampleRecord::loo_error
  std::vector<Histogram> pdfs;  // final, one per parameter (parameter units)
  // Final derived quantities (cg_height...: vehicles with heights and a PC
  // expansion only; empty otherwise).
  std::vector<DerivedSummary> derived;
  // The model gives the load transfer ratio (last_record.load_transfer_ratio,
  // samples.csv's last column).
  bool load_transfer_ratio = false;
  CoherenceCheck coherence;
  int nis_window_violations = 0;
  PredictiveCheck predictive;   // batch methods, grid and EnKF (health.predictive_check)
  int rejected_samples = 0;     // one-step: gated or rolled back
  int damped_updates = 0;       // updates scaled down by the support rule
  int reopened = 0;             // one-step: times the uncertainty was re-opened
  int relinearized = 0;         // one-step: re-linearisations (filter.relinearize)
  bool load_tracking = false;                 // one-step with reopen mode load
  std::vector<LoadChangeEvent> load_changes;  // what it found
  // One-step with filter.horizon.clock_offset: the estimate (s) at the end; NaN: none.
  double clock_offset = std::numeric_limits<double>::quiet_NaN();
  double clock_offset_std = std::numeric_limits<double>::quiet_NaN();
  // One-step with filter.horizon's nuisance values: their estimates at the end.
  std::vector<NuisanceValue> nuisance;
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

}  // namespace pc_ekf
