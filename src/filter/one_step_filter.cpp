#include "pc_ekf/filter/one_step_filter.h"
#include "pc_ekf/filter/prior_correction.h"
#include "pc_ekf/filter/reopen_chance.h"

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "pc_ekf/pc/pc_statistics.h"

namespace pc_ekf {

std::string measurementProblem(const Measurement& m, int channel_count) {
  if (!std::isfinite(m.time)) return "non-finite time stamp";
  if (static_cast<Eigen::Index>(m.channels.size()) != m.values.size()) {
    return "channel list and values differ in length";
  }
  for (std::size_t i = 0; i < m.channels.size(); ++i) {
    if (m.channels[i] < 0 || m.channels[i] >= channel_count) return "unknown channel index";
    if (i > 0 && m.channels[i] <= m.channels[i - 1]) return "channels not strictly ascending";
  }
  if (!m.values.allFinite()) return "non-finite measurement value";
  return "";
}

// A deferred re-run (docs/realtime.md): a filter of its own, started from the
// working prior on a single-threaded copy of the propagator, fed the kept
// samples and then each new one by the filter that started it, on a thread
// of its own. It stops after `target` samples: the swap sample.
class DeferredRerun {
 public:
  DeferredRerun(std::shared_ptr<const PcPropagator> propagator, const OneStepSettings& settings,
                const Eigen::MatrixXd& x0, std::vector<Measurement> samples, int target)
      : filter_(std::move(propagator), withoutRelinearization(settings)),
        samples_(std::move(samples)),
        target_(target) {
    filter_.x_ = x0;  // as relinearize(): the prior's time 0, no samples, health reset
    thread_ = std::thread([this] { run(); });
  }
  ~DeferredRerun() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      cancelled_ = true;
    }
    wake_.notify_all();
    if (thread_.joinable()) thread_.join();
  }
  void add(const Measurement& m) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (static_cast<int>(samples_.size()) < target_) samples_.push_back(m);
    }
    wake_.notify_all();
  }
  // Waits for the last sample; true when the worker was still busy.
  bool finish() {
    std::unique_lock<std::mutex> lock(mutex_);
    const bool late = !done_;
    done_wake_.wait(lock, [this] { return done_; });
    return late;
  }
  OneStepFilter& filter() { return filter_; }
  const StepResult& last() const { return last_; }
  bool reopened() const { return reopened_; }
  bool failed() const { return failed_; }

 private:
  static OneStepSettings withoutRelinearization(OneStepSettings s) {
    s.relinearize.shrink = 0.0;  // the re-run itself does not restart
    return s;
  }
  void run() {
    for (int i = 0; i < target_; ++i) {
      Measurement m;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [&] { return cancelled_ || static_cast<int>(samples_.size()) > i; });
        if (cancelled_) break;
        m = samples_[static_cast<std::size_t>(i)];
      }
      try {
        last_ = filter_.process(m);
      } catch (const std::exception&) {
        failed_ = true;  // checked samples: not expected; the swap is then skipped
        break;
      }
      reopened_ = reopened_ || last_.reopened;
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      done_ = true;
    }
    done_wake_.notify_all();
  }

  OneStepFilter filter_;
  std::vector<Measurement> samples_;  // guarded by mutex_
  const int target_;
  StepResult last_;
  bool reopened_ = false, failed_ = false;
  bool cancelled_ = false, done_ = false;  // guarded by mutex_
  std::mutex mutex_;
  std::condition_variable wake_, done_wake_;
  std::thread thread_;
};

OneStepFilter::OneStepFilter(std::shared_ptr<const PcPropagator> propagator,
                             const OneStepSettings& settings)
    : propagator_(std::move(propagator)),
      settings_(settings),
      health_(*propagator_, settings.health),
      rates_(rateSettings(settings.health, settings.innovation_gate)),
      x_(propagator_->priorState()) {
  const int n = propagator_->parameterCount();
  prior_theta_ = x_.bottomRows(n);
  lower_.resize(n);
  upper_.resize(n);
  for (int i = 0; i < n; ++i) {
    lower_[i] = propagator_->mapping().lowerBound(i);
    upper_[i] = propagator_->mapping().upperBound(i);
  }
  if (settings_.drift.size() != 0 && settings_.drift.size() != n) {
    throw std::invalid_argument("drift: one intensity per uncertain parameter expected");
  }
  const SettingBreach breach = relinearizeBreach(settings_.relinearize);
  if (breach.broken()) {
    throw std::invalid_argument("relinearize: " + breach.setting + " " + breach.value + ", needs " +
                                breach.needs);
  }
  if (settings_.horizon.window > 0.0) {
    horizon_ = std::make_unique<MovingHorizon>(*propagator_, settings_.horizon);
    settings_.relinearize.shrink = 0.0;  // the horizon's re-runs take its place
    x_.bottomRows(n) = horizon_->coefficients();
  }
  const std::vector<std::string> names = propagator_->mapping().names();
  for (int i = 0; i < n; ++i) {
    if (names[static_cast<std::size_t>(i)].rfind("added_mass", 0) == 0) load_rows_.push_back(i);
  }
  if (settings_.reopen.mode == ReopenMode::kLoad && (!horizon_ || load_rows_.empty())) {
    throw std::invalid_argument(
        "reopen mode load needs filter.linearization: mean and an uncertain added_mass");
  }
  // A load change is rewound to where it began: the violation run and the
  // NIS window before it, twice over for a change that builds up slowly.
  if (settings_.reopen.mode == ReopenMode::kLoad) {
    const MechanicalModel& model = propagator_->model();
    if (model.zero() == ZeroConvention::kRest) {
      throw std::invalid_argument(
          "reopen mode load needs measurement.zero: tare (with rest the readings' zero is the "
          "vehicle with the load it started with)");
    }
    const auto& ch = model.channelNames();
    if (std::find(ch.begin(), ch.end(), "gyro_y") != ch.end()) {
      throw std::invalid_argument(
          "reopen mode load: a model whose body angles integrate gyro_x and gyro_y from the "
          "start (the full car) is not supported yet");
    }
    horizon_->keepRecent(changeSpan());
  }
  startRelinearization();
  // The re-open rule's chance rate is simulated at the first sample with a
  // given channel count (a few ms, once per process and count): the model's
  // every channel is rarely what a sample carries.
}

double OneStepFilter::reopenChance(int dof) {
  if (settings_.reopen.mode == ReopenMode::kOff || dof < 1) return 0.0;
  if (dof >= static_cast<int>(reopen_chance_.size())) {
    reopen_chance_.resize(static_cast<std::size_t>(dof) + 1, -1.0);
  }
  double& p = reopen_chance_[static_cast<std::size_t>(dof)];
  if (p < 0.0) {
    p = chanceReopenPerSample(settings_.health.nis_window, dof, settings_.health.nis_confidence,
                              settings_.reopen.after);
  }
  return p;
}

const Eigen::VectorXd& OneStepFilter::driftFor(const Measurement& m) const {
  return m.standing && settings_.drift_standing.size() != 0 ? settings_.drift_standing
                                                            : settings_.drift;
}

OneStepFilter::~OneStepFilter() = default;

void OneStepFilter::cancelRerun() { rerun_.reset(); }

void OneStepFilter::setRerun(std::shared_ptr<const PcPropagator> propagator,
                             std::function<void()> before_feed) {
  rerun_propagator_ = std::move(propagator);
  before_feed_ = std::move(before_feed);
}

void OneStepFilter::startRelinearization() {
  cancelRerun();
  kept_.clear();
  restarts_ = 0;
  relinearizing_ = settings_.relinearize.shrink > 0.0 && settings_.relinearize.max_restarts > 0;
  start_theta_ = x_.bottomRows(propagator_->parameterCount());
  start_stddev_ = pcStddev(start_theta_);
}

void OneStepFilter::endRelinearization() {
  cancelRerun();
  relinearizing_ = false;
  kept_.clear();
  kept_.shrink_to_fit();
}

double OneStepFilter::gateBound(int dof) {
  if (dof >= static_cast<int>(gate_cache_.size())) {
    gate_cache_.resize(dof + 1, std::numeric_limits<double>::quiet_NaN());
  }
  double& b = gate_cache_[dof];
  if (std::isnan(b)) b = chiSquareQuantile(1.0 - settings_.innovation_gate, dof);
  return b;
}

void OneStepFilter::reset() {
  cancelRerun();
  x_ = propagator_->priorState();
  if (horizon_) {
    horizon_->reset();
    x_.bottomRows(propagator_->parameterCount()) = horizon_->coefficients();
  }
  lagged_.clear();
  t_ = 0.0;
  samples_ = 0;
  rejected_ = 0;
  violations_ = 0;
  load_changes_ = 0;
  load_change_time_ = std::numeric_limits<double>::quiet_NaN();
  health_.reset();
  rates_.reset(0.0);
  working_theta_.resize(0, 0);
  startRelinearization();
}

void OneStepFilter::restore(const Eigen::MatrixXd& x, double time, int samples,
                            const Eigen::MatrixXd& working) {
  if (x.rows() != x_.rows() || x.cols() != x_.cols()) {
    throw std::invalid_argument("restore: state size does not match the filter");
  }
  if (working.size() > 0 &&
      (working.rows() != propagator_->parameterCount() || working.cols() != x_.cols())) {
    throw std::invalid_argument("restore: working prior size does not match the filter");
  }
  x_ = x;
  t_ = time;
  samples_ = samples;
  violations_ = 0;
  health_.reset();
  if (rates_.samples() == 0) rates_.reset(time);  // a fresh filter: the run starts here
  working_theta_ = working;
  if (horizon_) horizon_->restore(x_.bottomRows(propagator_->parameterCount()));
  endRelinearization();
}

StepResult OneStepFilter::process(const Measurement& m) {
  StepResult r = processSample(m);
  if (r.reopened) working_theta_.resize(0, 0);  // re-opened towards the prior
  report(r);
  return r;
}

void OneStepFilter::report(StepResult& r) const {
  if (settings_.relinearize.prior_correction && working_theta_.size() > 0 &&
      r.coefficients.allFinite() &&
      correctForPrior(prior_theta_, working_theta_, r.coefficients)) {
    r.mean = pcMean(r.coefficients);
    r.stddev = pcStddev(r.coefficients);
  }
}

StepResult OneStepFilter::processSample(const Measurement& m) {
  const MechanicalModel& model = propagator_->model();
  const std::string problem = measurementProblem(m, static_cast<int>(model.channelNames().size()));
  if (!problem.empty()) throw std::invalid_argument("measurement rejected: " + problem);
  if (m.time < t_) throw std::invalid_argument("measurement rejected: time before the filter's");
  StepResult r = step(m);
  if (!relinearizing_) return r;
  if (r.reopened) {  // the kept samples describe the load before the change
    endRelinearization();
    return r;
  }
  kept_.push_back(m);
  if (rerun_) {  // a deferred re-run: feed it; no other restart meanwhile
    if (before_feed_) before_feed_();
    rerun_->add(m);
    if (samples_ < swap_after_) {
      r.rerun_pending = true;
      r.rerun_swap_after = swap_after_;
      return r;
    }
    return swapInRerun(r);
  }
  // Due when a parameter has shrunk below `shrink` x its start; then every
  // parameter whose working prior would be narrower than its start moves.
  const RelinearizeSettings& rl = settings_.relinearize;
  const Eigen::ArrayXd start = start_stddev_.array();
  if (r.forecast.ok && (r.stddev.array() <= rl.shrink * start).any()) {
    const Eigen::ArrayXi narrowed = (rl.width * r.stddev.array() < start).cast<int>();
    if (rl.defer > 0.0) {
      deferRelinearization(r, narrowed);
      if (rerun_) {
        r.rerun_pending = true;
        r.rerun_swap_after = swap_after_;
      }
      return r;
    }
    return relinearize(r, narrowed);
  }
  if (static_cast<int>(kept_.size()) >= settings_.relinearize.max_samples) endRelinearization();
  return r;
}

bool OneStepFilter::workingPrior(const StepResult& r, const Eigen::ArrayXi& narrowed,
                                 Eigen::MatrixXd* theta, Eigen::MatrixXd* x0) {
  const RelinearizeSettings& rl = settings_.relinearize;
  // The parameters that have narrowed start again around their estimate; the
  // others keep the distribution they started from (the prior, at first).
  *theta = propagator_->mapping().workingCoefficients(propagator_->basis(), r.mean,
                                                      rl.width * r.stddev, rl.prior_correction);
  for (int i = 0; i < theta->rows(); ++i) {
    // With the prior put back, a working prior cut short (a support narrower
    // than it) would make P_q^-1 - Q^-1 a difference of nearly equal numbers:
    // such a parameter keeps the distribution it started from.
    const bool cut = rl.prior_correction &&
                     pcStddev(theta->row(i))[0] < 0.75 * rl.width * r.stddev[i];
    if (!narrowed[i] || cut) {
      theta->row(i) = start_theta_.row(i);
    } else if (pcStddev(theta->row(i))[0] <= 0.0) {
      endRelinearization();  // a mean on the support's edge: no working prior
      return false;
    }
  }
  try {
    *x0 = propagator_->stateFor(*theta);
  } catch (const std::invalid_argument&) {
    endRelinearization();
    return false;
  }
  return true;
}

void OneStepFilter::deferRelinearization(const StepResult& r, const Eigen::ArrayXi& narrowed) {
  Eigen::MatrixXd x0;
  if (!workingPrior(r, narrowed, &rerun_theta_, &x0)) return;
  const int kept = static_cast<int>(kept_.size());
  const int delay =
      static_cast<int>(std::ceil(settings_.relinearize.defer * static_cast<double>(kept)));
  swap_after_ = samples_ + delay;
  if (!rerun_propagator_) rerun_propagator_ = propagator_->withThreads(1);
  if (before_feed_) before_feed_();
  rerun_ = std::make_unique<DeferredRerun>(rerun_propagator_, settings_, x0, kept_,
                                           kept + delay);
}

StepResult OneStepFilter::swapInRerun(const StepResult& live) {
  late_swaps_ += rerun_->finish();
  if (rerun_->failed()) {  // the live filter's result stands
    endRelinearization();
    return live;
  }
  OneStepFilter& f = rerun_->filter();
  x_ = f.x_;
  t_ = f.t_;
  samples_ = f.samples_;
  rejected_ = f.rejected_;
  violations_ = f.violations_;
  health_ = f.health_;
  rates_ = f.rates_;
  StepResult last = rerun_->last();
  const bool reopened = rerun_->reopened();
  rerun_.reset();
  ++restarts_;
  start_theta_ = rerun_theta_;
  start_stddev_ = pcStddev(rerun_theta_);
  working_theta_ = rerun_theta_;
  if (restarts_ >= settings_.relinearize.max_restarts || reopened) endRelinearization();
  last.relinearized = true;
  last.restarts = restarts_;
  last.rejected = rejected_;
  return last;
}

StepResult OneStepFilter::relinearize(const StepResult& r, const Eigen::ArrayXi& narrowed) {
  const RelinearizeSettings& rl = settings_.relinearize;
  Eigen::MatrixXd theta, x0;
  if (!workingPrior(r, narrowed, &theta, &x0)) return r;
  const int restarts = restarts_ + 1;
  x_ = x0;
  t_ = 0.0;
  samples_ = 0;
  rejected_ = 0;
  violations_ = 0;
  health_.reset();
  rates_.reset(0.0);
  StepResult last;
  bool reopened = false;
  for (const Measurement& m : kept_) {  // step() leaves kept_ alone
    last = step(m);
    reopened = reopened || last.reopened;
  }
  restarts_ = restarts;
  start_theta_ = theta;
  start_stddev_ = pcStddev(theta);
  working_theta_ = theta;
  if (restarts_ >= rl.max_restarts || reopened) endRelinearization();
  last.relinearized = true;
  last.restarts = restarts_;
  return last;
}

StepResult OneStepFilter::step(const Measurement& m) {
  StepResult r;
  const double dt = m.time - t_;
  if (horizon_) {
    horizonUpdate(m, dt, r);
  } else {
    collocationUpdate(m, dt, r);
  }
  r.coefficients = x_.bottomRows(propagator_->parameterCount());
  r.mean = pcMean(r.coefficients);
  r.stddev = pcStddev(r.coefficients);
  // The window sees a gated sample's NIS clipped at the gate: a persistent
  // misfit still breaks the window, one wild outlier does not dominate it.
  // The gated sample itself counts in the gate's rate (rates_, below), which
  // fails health beyond the gate's expected fraction (docs/method.md §5.9).
  UpdateDiagnostics seen = r.update;
  if (r.gated) seen.nis = std::min(seen.nis, gateBound(r.update.channels));
  if (r.rolled_back) seen.finite = false;
  r.health = health_.assess(seen, r.forecast, r.coefficients);
  r.health.nis = r.update.nis;
  r.health.gated = r.gated;
  r.health.damped = r.damping < 1.0;
  r.rejected = rejected_;
  r.restarts = restarts_;
  // Only a window above its upper bound counts towards a re-open: a load that
  // changes makes the innovations large. A window below its lower bound (the
  // noise overstated) stays a health finding; widening would not mend it.
  const bool above = r.health.nis_window_outside && r.health.nis_window_mean > r.health.window_upper;
  violations_ = above ? violations_ + 1 : 0;
  if (settings_.reopen.mode != ReopenMode::kOff && violations_ >= settings_.reopen.after) {
    if (settings_.reopen.mode != ReopenMode::kLoad) {
      reopen();
      r.reopened = true;
    } else {
      r.reopened = r.load_reset = reloadFromChange(r);
      r.rejected = rejected_;
    }
    if (r.reopened) {
      health_.reset();
      r.health.reopened = true;
    }
    violations_ = 0;
  }
  r.load_changes = load_changes_;
  r.load_change_time = load_change_time_;
  if (horizon_) {
    r.clock_offset = horizon_->clockOffset();
    r.clock_offset_std = horizon_->clockOffsetStd();
    if (horizon_->nuisance()) {
      const MovingHorizon& h = *horizon_;
      const NuisanceValue all[] = {{"cross_fall_rad", h.crossFall(), h.crossFallStd()},
                                   {"accel_y_bias", h.accelYBias(), h.accelYBiasStd()},
                                   {"accel_z_bias", h.accelZBias(), h.accelZBiasStd()},
                                   {"gyro_x_bias", h.gyroBias(), h.gyroBiasStd()}};
      for (const NuisanceValue& v : all) {
        if (std::isfinite(v.mean)) r.nuisance.push_back(v);
      }
    }
  }
  const int support = r.health.mass_outside_support.size() > 0 ? r.health.support_exceeded : -1;
  // The rule's chance re-opens at this sample's dof: a correct model at a
  // high sampling rate re-opens now and then, and that is no misfit.
  r.health.rates = rates_.add(r.time, r.gated, r.health.damped, r.reopened, support,
                              reopenChance(r.update.channels));
  return r;
}

void OneStepFilter::reopen() {
  const int np = propagator_->parameterCount();
  if (!horizon_) {
    reopenExtendedState(x_, static_cast<int>(x_.rows()) - np,
                        propagator_->priorState().bottomRows(np), settings_.reopen);
    return;
  }
  // width, prior: every parameter (a load change goes through reloadFromChange)
  std::vector<int> rows(static_cast<std::size_t>(np));
  for (int i = 0; i < np; ++i) rows[static_cast<std::size_t>(i)] = i;
  horizon_->reopen(rows);
  x_.bottomRows(np) = horizon_->coefficients();
}

double OneStepFilter::changeLevel(int dof) {
  // The NIS's 0.99 quantile: a sample of the unchanged load is below it 99
  // times in 100, so the change point is rarely placed before the change.
  if (dof >= static_cast<int>(change_level_.size())) {
    change_level_.resize(static_cast<std::size_t>(dof) + 1, -1.0);
  }
  double& q = change_level_[static_cast<std::size_t>(dof)];
  if (q < 0.0) q = chiSquareQuantile(0.99, dof);
  return q;
}

int OneStepFilter::changeSpan() const {
  return settings_.reopen.after + 2 * settings_.health.nis_window;
}

bool OneStepFilter::reloadFromChange(StepResult& r) {
  // The samples since the change began describe the new load: the filter
  // goes back to its state before them (so the vehicle values keep only what
  // the old load's samples taught), the load starts from its prior, and those
  // samples are assimilated again. Their first verdicts (gated, damped: the
  // change seen through the old load) are replaced by the new ones. The
  // first samples of a change can be transitional (a sensor's averaging, the
  // load settling): the change point is moved on, up to kChangeShifts
  // samples, until the new load explains every sample after it (no gated).
  constexpr int kChangeShifts = 5;
  const int np = propagator_->parameterCount();
  const int back = horizon_->samplesSinceChange(violations_ + settings_.health.nis_window,
                                                [this](int dof) { return changeLevel(dof); });
  const auto gate = [this](int dof) {
    return settings_.innovation_gate > 0.0 ? gateBound(dof) : 0.0;
  };
  // A change leaves every sample after it misfit, so its start lies at
  // least about `after` samples back; a run of chance excursions of the
  // windowed NIS does not (its CUSUM start is the last few samples): that
  // is no load change, and nothing is reset.
  if (back < std::max(2, settings_.reopen.after / 2)) return false;
  const MovingHorizon before(*horizon_);
  std::unique_ptr<MovingHorizon> best;
  std::vector<SampleVerdict> best_verdicts;
  HorizonStep best_last;
  int best_gated = std::numeric_limits<int>::max();
  double best_start = t_;
  for (int shift = 0; shift <= kChangeShifts && shift < back; ++shift) {
    auto trial = std::make_unique<MovingHorizon>(before);
    const std::vector<Measurement> again = trial->rewind(back - shift);
    trial->reopen(load_rows_);
    std::vector<SampleVerdict> verdicts(static_cast<std::size_t>(shift));  // the change itself
    HorizonStep h;
    int gated = 0;
    for (const Measurement& m : again) {
      if (settings_.drift.size() != 0) trial->drift(driftFor(m), m.time - trial->lastTime());
      h = trial->process(m, settings_.noise, gate, settings_.support == SupportRule::kDamp);
      verdicts.push_back({h.gated, h.damping < 1.0});
      gated += h.gated;
    }
    if (gated < best_gated) {
      best_start = again.empty() ? t_ : again.front().time;
      best = std::move(trial);
      best_verdicts = std::move(verdicts);
      best_last = h;
      best_gated = gated;
    }
    if (gated == 0) break;
  }
  if (!best) {  // nothing kept to rewind to: the load afresh from here
    horizon_->reopen(load_rows_);
  } else {
    horizon_ = std::move(best);
    load_change_time_ = best_start;
    ++load_changes_;
    rejected_ += static_cast<int>(best_verdicts.back().gated) - static_cast<int>(r.gated);
    r.gated = r.health.gated = best_verdicts.back().gated;
    r.health.damped = best_verdicts.back().damped;
    r.damping = best_last.damping;
    r.update = best_last.update;
    best_verdicts.pop_back();  // this sample's verdict is added to the rates below
    rejected_ += rates_.revise(best_verdicts);
  }
  x_.bottomRows(np) = horizon_->coefficients();
  r.coefficients = x_.bottomRows(np);
  r.mean = pcMean(r.coefficients);
  r.stddev = pcStddev(r.coefficients);
  return true;
}

void OneStepFilter::horizonUpdate(const Measurement& m, double dt, StepResult& r) {
  const int np = propagator_->parameterCount();
  if (settings_.drift.size() != 0) horizon_->drift(driftFor(m), dt);
  t_ = m.time;
  r.index = ++samples_;
  r.time = m.time;
  const auto gate = [this](int dof) {
    return settings_.innovation_gate > 0.0 ? gateBound(dof) : 0.0;
  };
  // With a clock offset the horizon takes each sample once the inputs after
  // it are in (readingLag): the samples wait here, in order.
  lagged_.push_back(m);
  const double lag = horizon_->readingLag(dt);
  while (!lagged_.empty() && lagged_.front().time <= m.time - lag) {
    const Measurement& next = lagged_.front();
    const HorizonStep h = horizon_->process(next, settings_.noise, gate,
                                            settings_.support == SupportRule::kDamp);
    r.update = h.update;
    r.gated = h.gated;
    r.damping = h.damping;
    if (!next.channels.empty() && !h.update.finite) {
      r.rolled_back = true;
      ++rejected_;
    } else if (h.gated) {
      ++rejected_;
    }
    r.relinearized = r.relinearized || h.reruns > 0;
    lagged_.pop_front();
  }
  x_.bottomRows(np) = horizon_->coefficients();
}

void OneStepFilter::collocationUpdate(const Measurement& m, double dt, StepResult& r) {
  const MechanicalModel& model = propagator_->model();
  r.forecast = propagator_->forecast(x_, t_, m.time);
  const int ns = propagator_->stateCount();
  if (r.forecast.ok && settings_.drift.size() != 0) {
    applyDrift(x_, ns, driftFor(m), dt);
  }
  t_ = m.time;
  r.index = ++samples_;
  r.time = m.time;
  if (!m.channels.empty() && r.forecast.ok) {
    // Observation coefficients Z = H X_y of the observed channels.
    z_coeffs_.resize(static_cast<Eigen::Index>(m.channels.size()), x_.cols());
    for (std::size_t i = 0; i < m.channels.size(); ++i) {
      z_coeffs_.row(i).noalias() =
          model.observationMatrix().row(m.channels[i]).lazyProduct(x_.topRows(ns));
    }
    x_before_ = x_;
    const NoiseWhitening white(settings_.noise, m);
    Eigen::VectorXd values = m.values;
    white.whiten(values);
    white.whiten(z_coeffs_);
    r.update = pcKalmanUpdate(x_, z_coeffs_, values, white.variances(), settings_.rule);
    safeguard(r);
  } else {
    r.update.finite = x_.allFinite();
  }
}

void OneStepFilter::safeguard(StepResult& r) {
  const int np = propagator_->parameterCount();
  if (!r.update.finite || !x_.allFinite()) {
    // Keep the forecast: a non-finite state would poison every later sample.
    x_ = x_before_;
    r.rolled_back = true;
    ++rejected_;
    return;
  }
  if (settings_.innovation_gate > 0.0 && r.update.nis > gateBound(r.update.channels)) {
    x_ = x_before_;
    r.gated = true;
    ++rejected_;
    return;
  }
  if (settings_.support == SupportRule::kDamp) {
    r.damping = supportDamping(x_before_.bottomRows(np).col(0), x_.bottomRows(np).col(0), lower_,
                               upper_);
    if (r.damping < 1.0) x_ = x_before_ + r.damping * (x_ - x_before_);
  }
}

}  // namespace pc_ekf
