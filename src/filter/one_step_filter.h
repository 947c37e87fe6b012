// One-step-at-a-time PC-EKF (docs/method.md §4.2, §4.3): forecast to each sample's
// time, update with the paper or the square-root rule, report the
// parameters' distribution and health after every sample.
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <functional>
#include <deque>
#include <limits>
#include <memory>
#include <vector>

#include "pc_ekf/filter/health.h"
#include "pc_ekf/filter/kalman_update.h"
#include "pc_ekf/filter/measurement.h"
#include "pc_ekf/filter/moving_horizon.h"
#include "pc_ekf/filter/pc_propagator.h"
#include "pc_ekf/filter/update_safeguards.h"

namespace pc_ekf {

// The safeguards, and the update rule, R, health checks and gate.
struct OneStepSettings : SafeguardSettings {
  UpdateRule rule = UpdateRule::kSquareRoot;
  NoiseModel noise;
  HealthSettings health;
  // Innovation gate: a sample whose NIS exceeds the chi-square quantile
  // 1 - innovation_gate (its channel count as dof) is not used (0 = off).
  double innovation_gate = 0.0;
};

struct StepResult {
  int index = 0;  // 1-based sample count since the prior
  double time = 0.0;
  Eigen::VectorXd mean, stddev;  // parameters
  Eigen::MatrixXd coefficients;  // parameters x S
  UpdateDiagnostics update;
  ForecastReport forecast;
  HealthStatus health;
  bool gated = false;     // NIS above the innovation gate: the update was not applied
  bool rolled_back = false;  // the update was not finite: the forecast state was kept
  double damping = 1.0;   // fraction of the update applied (support rule)
  bool reopened = false;  // uncertainty re-opened after this sample
  bool load_reset = false;  // reopen.mode load: the load's estimate started afresh
  int load_changes = 0;     // load resets since the prior
  double load_change_time = std::numeric_limits<double>::quiet_NaN();  // the last one's first sample
  // linearization mean with filter.horizon.clock_offset: the offset (s), its std; NaN: none.
  double clock_offset = std::numeric_limits<double>::quiet_NaN();
  double clock_offset_std = std::numeric_limits<double>::quiet_NaN();
  std::vector<NuisanceValue> nuisance;  // filter.horizon's nuisance values; empty: none
  int rejected = 0;       // samples gated or rolled back since the prior
  bool relinearized = false;  // the samples so far were re-run from a working prior
  int restarts = 0;           // re-linearisations since the prior
  // relinearize.defer > 0: a re-run is under way on the worker (its state
  // replaces the filter's after sample `rerun_swap_after`).
  bool rerun_pending = false;
  int rerun_swap_after = 0;
};

class DeferredRerun;

class OneStepFilter {
  friend class DeferredRerun;

 public:
  OneStepFilter(std::shared_ptr<const PcPropagator> propagator, const OneStepSettings& settings);
  ~OneStepFilter();
  OneStepFilter(const OneStepFilter&) = delete;
  OneStepFilter& operator=(const OneStepFilter&) = delete;

  // Throws std::invalid_argument (state untouched) when the sample is before
  // the filter's time, has unknown/duplicate channels or non-finite values.
  StepResult process(const Measurement& m);
  // health.support_every != 1: the mass outside the support of the
  // sample r (this filter's newest), filled in (HealthMonitor::assessSupport).
  void assessSupport(StepResult* r) { health_.assessSupport(r->coefficients, &r->health); }
  void reset();

  const PcPropagator& propagator() const { return *propagator_; }
  const Eigen::MatrixXd& state() const { return x_; }  // (states + parameters) x S
  double time() const { return t_; }
  int samples() const { return samples_; }
  const OneStepSettings& settings() const { return settings_; }
  // Restores a state (same propagator and settings); the rejected count is
  // kept, re-linearisation ends (the kept samples no longer lead to x).
  // working: the working prior x was updated from (workingPrior()); empty:
  // the prior. Throws std::invalid_argument for a wrong size.
  void restore(const Eigen::MatrixXd& x, double time, int samples,
               const Eigen::MatrixXd& working = Eigen::MatrixXd());
  // The working prior's parameter coefficients the state was updated from,
  // when relinearize.prior_correction is on and a restart came; else empty.
  const Eigen::MatrixXd& workingPrior() const { return working_theta_; }
  // r's parameters with the working prior's information replaced by the
  // prior's (relinearize.prior_correction; prior_correction.h); process()
  // applies it to every result, a caller reporting state() itself calls it.
  void report(StepResult& r) const;
  int rejected() const { return rejected_; }
  // Earliest time the filter may still need the road (or a road-free
  // model's inputs) from: a re-run, or the moving horizon's window.
  double roadNeededFrom() const {
    if (relinearizing_) return 0.0;
    return horizon_ ? std::min(t_, horizon_->windowStart()) : t_;
  }
  // Deferred re-runs: their propagator (default: a single-threaded copy of
  // this one, sharing the model and its road) and a call made on this thread
  // before the worker starts and before each sample it is fed (e.g. to hand
  // it a newer copy of a road that grows).
  void setRerun(std::shared_ptr<const PcPropagator> propagator, std::function<void()> before_feed);
  // Deferred re-runs (relinearize.defer > 0) whose worker had not finished
  // when their swap came, so that the sample waited for it.
  int lateSwaps() const { return late_swaps_; }
  // linearization mean: point runs of the model (n + 1 per sample and
  // re-run sample); 0 for collocation, whose cost the propagator counts.
  long horizonEvaluations() const { return horizon_ ? horizon_->evaluations() : 0; }

 private:
  std::shared_ptr<const PcPropagator> propagator_;
  OneStepSettings settings_;
  HealthMonitor health_;
  SafeguardRateMonitor rates_;  // the safeguards' rates since the prior (docs/method.md §5.9)
  // Gate threshold for `dof` channels (cached: quantiles are iterative).
  double gateBound(int dof);
  void safeguard(StepResult& r);
  StepResult step(const Measurement& m);
  // The update of step(): by collocation, or at the mean (horizon_).
  void collocationUpdate(const Measurement& m, double dt, StepResult& r);
  void horizonUpdate(const Measurement& m, double dt, StepResult& r);
  void reopen();
  // reopen.mode load: back to where the change began, the load afresh, the
  // samples since then again (r: this sample's result, updated). False: the
  // misfit is no load change (nothing done).
  bool reloadFromChange(StepResult& r);
  int changeSpan() const;  // samples the horizon keeps for that
  double changeLevel(int dof);  // NIS level above which a sample counts as changed
  std::vector<double> change_level_;
  int load_changes_ = 0;
  double load_change_time_ = std::numeric_limits<double>::quiet_NaN();
  // Re-runs the kept samples from a working prior around r; r when impossible.
  StepResult relinearize(const StepResult& r, const Eigen::ArrayXi& narrowed);
  // The working prior's parameter coefficients around r (false: none).
  bool workingPrior(const StepResult& r, const Eigen::ArrayXi& narrowed, Eigen::MatrixXd* theta,
                    Eigen::MatrixXd* x0);
  // relinearize.defer > 0: starts the re-run of the kept samples on a worker.
  void deferRelinearization(const StepResult& r, const Eigen::ArrayXi& narrowed);
  // After the swap sample: the worker's state becomes the filter's.
  StepResult swapInRerun(const StepResult& live);
  void cancelRerun();
  void startRelinearization();
  void endRelinearization();

  Eigen::MatrixXd x_;
  Eigen::MatrixXd x_before_;  // state before the update (gate, roll-back, damping)
  Eigen::MatrixXd z_coeffs_;  // per-sample buffer
  Eigen::VectorXd lower_, upper_;  // parameter supports
  std::vector<double> gate_cache_;
  int rejected_ = 0;
  int violations_ = 0;  // consecutive samples with the windowed NIS outside
  double t_ = 0.0;
  int samples_ = 0;
  bool relinearizing_ = false;
  std::vector<Measurement> kept_;   // since the (working) prior
  Eigen::MatrixXd start_theta_;     // parameter coefficients at that start
  Eigen::VectorXd start_stddev_;
  // The prior the state's parameters were updated from, when it is a working
  // prior (relinearize.prior_correction); empty when it is the prior itself.
  Eigen::MatrixXd working_theta_;
  Eigen::MatrixXd prior_theta_;  // the prior's parameter coefficients (report's reference)
  // The re-open rule's chance per sample by dof (-1: not yet simulated; 0
  // with re-opens off): looked up once per channel count, not per sample.
  double reopenChance(int dof);
  // The walk over the interval sample m ends (standing: drift_standing).
  const Eigen::VectorXd& driftFor(const Measurement& m) const;
  std::vector<double> reopen_chance_;
  StepResult processSample(const Measurement& m);
  int restarts_ = 0;
  std::unique_ptr<MovingHorizon> horizon_;  // filter.linearization: mean
  std::deque<Measurement> lagged_;          // samples the horizon has not taken yet
  std::vector<int> load_rows_;              // reopen.mode load: added_mass...
  std::unique_ptr<DeferredRerun> rerun_;  // a deferred re-run under way
  Eigen::MatrixXd rerun_theta_;           // its working prior's parameter coefficients
  int swap_after_ = 0;                    // its swap: after this sample
  std::shared_ptr<const PcPropagator> rerun_propagator_;  // single-threaded copy
  std::function<void()> before_feed_;
  int late_swaps_ = 0;
};

// Checks a measurement against a model's channels; "" when fine.
std::string measurementProblem(const Measurement& m, int channel_count);

}  // namespace pc_ekf
