#include "pc_ekf/ros/estimator_run.h"

#include <cmath>
#include <limits>
#include <sstream>

#include "pc_ekf/filter/batch_update.h"
#include "pc_ekf/health/predictive_check.h"
#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/io/offline_estimation.h"
#include "pc_ekf/pc/pc_statistics.h"
#include "pc_ekf/ros/message_conversion.h"

namespace pc_ekf {
namespace {

bool finiteResult(const StepResult& r) {
  return !r.health.non_finite && r.mean.allFinite() && r.stddev.allFinite() &&
         r.coefficients.allFinite();
}

// The state before a non-finite update, reported in place of the update.
StepResult fallbackResult(const StepResult& bad, const OneStepFilter& filter) {
  StepResult r = bad;
  r.coefficients = filter.state().bottomRows(filter.propagator().parameterCount());
  filter.report(r);
  r.mean = pcMean(r.coefficients);
  r.stddev = pcStddev(r.coefficients);
  r.health.non_finite = true;
  return r;
}

void zero(double& v) {
  if (!std::isfinite(v)) v = 0.0;
}

}  // namespace

void zeroNonFinite(ParameterEstimate& msg) {
  for (auto* array : {&msg.mean, &msg.stddev, &msg.xi_mean, &msg.xi_stddev, &msg.coefficients,
                      &msg.mass_outside_support, &msg.coherence_disagreement}) {
    for (double& v : *array) zero(v);
  }
  for (double* v : {&msg.time, &msg.nis, &msg.nis_lower, &msg.nis_upper, &msg.nis_window_mean,
                    &msg.nis_window_lower, &msg.nis_window_upper}) {
    zero(*v);
  }
}

EstimatorRun::EstimatorRun(const EstimatorConfig& config,
                           std::shared_ptr<const PcPropagator> propagator, bool pdfs,
                           std::shared_ptr<const SampledRoad> topic_road)
    : config_(config),
      propagator_(propagator),
      pdfs_(pdfs),
      full_(propagator, makeOneStepSettings(config)),
      decimated_(propagator, makeOneStepSettings(config)) {
  if (topic_road && config.safeguards.relinearize.defer > 0.0) {
    rerun_road_ = std::make_shared<RoadSnapshots>(std::move(topic_road));
    const auto update = [road = rerun_road_] { road->update(); };
    // One copy serves both filters' re-runs (each reads it, neither changes it).
    full_.setRerun(makePropagator(config, makeModel(config, rerun_road_))->withThreads(1), update);
    decimated_.setRerun(makePropagator(config, makeModel(config, rerun_road_))->withThreads(1),
                        update);
  }
}

double EstimatorRun::oldestTime() const {
  // A filter that may still re-linearise needs the road from its start.
  const double full = full_.roadNeededFrom();
  return config_.node.coherence_check ? std::min(full, decimated_.roadNeededFrom()) : full;
}

ParameterEstimate EstimatorRun::message(const StepResult& r, const ros::Time& stamp,
                                        bool latest_derived) const {
  EstimateContext context;
  context.stamp = stamp;
  context.method = "one_step";
  context.update_rule = toString(config_.update);
  if (latest_derived && derived_index_ >= 0) {
    context.derived = &derived_;
    context.derived_index = derived_index_;
  }
  return estimateMessage(r, *propagator_, full_.settings().health, context);
}

void EstimatorRun::project(const StepResult& r, bool pdf_due) {
  const bool due = derived_index_ < 0 || r.index % config_.node.derived_every == 0 || pdf_due ||
                   r.load_reset || r.relinearized;
  if (!due || !r.coefficients.allFinite()) return;
  derived_ = rolloverExpansions(propagator_->mapping(), propagator_->basis(), r.coefficients);
  derived_index_ = r.index;
}

SampleEstimate EstimatorRun::process(const Measurement& m, const ros::Time& stamp) {
  SampleEstimate out;
  const Eigen::MatrixXd before = full_.state();
  const Eigen::MatrixXd working_before = full_.workingPrior();
  const double time_before = full_.time();
  StepResult r = full_.process(m);
  pending_swap_ = r.rerun_pending ? r.rerun_swap_after : 0;
  const bool singular = r.update.singular;
  if (!finiteResult(r)) {
    // Keep the filter usable: the sample is skipped, its index still counted.
    full_.restore(before, time_before, r.index, working_before);
    r = fallbackResult(r, full_);
    out.non_finite = true;
  }
  out.health = r.health;

  const int k = config_.health.coherence_decimation;
  if (config_.node.coherence_check && r.index % k == 0) {
    const Eigen::MatrixXd coarse_before = decimated_.state();
    const Eigen::MatrixXd coarse_working = decimated_.workingPrior();
    const double coarse_time = decimated_.time();
    const StepResult d = decimated_.process(m);
    if (finiteResult(d) && !out.non_finite) {
      disagreement_ = coherenceDisagreement(r.mean, r.stddev, d.mean, d.stddev);
    } else if (!finiteResult(d)) {
      decimated_.restore(coarse_before, coarse_time, d.index, coarse_working);
      out.coherence_non_finite = true;
    }
  }

  const bool pdf_due =
      pdfs_ && r.index % config_.node.pdf_every == 0 && r.coefficients.allFinite();
  project(r, pdf_due);  // after a non-finite update: of the state kept
  out.estimate = message(r, stamp);
  // The tyres' load transfer at this sample, at the posterior mean (models that give it).
  const MechanicalModel& model = propagator_->model();
  if (model.hasLoadTransferRatio() && r.mean.size() > 0 && r.mean.allFinite()) {
    out.estimate.load_transfer_ratio =
        model.loadTransferRatio(propagator_->mapping().fullParameters(r.mean), r.time);
  }
  if (disagreement_) {
    setCoherence(out.estimate, *disagreement_, k, config_.health.coherence_threshold);
  }
  if (out.non_finite) {
    out.estimate.healthy = false;
    out.estimate.warnings.push_back(
        singular ? "innovation covariance numerically singular (a channel's predicted spread "
                   "and noise below round-off): sample not used, parameters are those before it"
                 : "update produced non-finite values: sample not used, parameters are those "
                   "before it");
    zeroNonFinite(out.estimate);
  }

  if (batch_series_.size() < static_cast<std::size_t>(config_.node.max_batch_samples)) {
    if (m.input_slopes.size() == 0) {
      batch_series_.push_back(m);
    } else {
      // The batch methods take each sample's inherited covariance, not the
      // input-noise states' slopes: not kept (about 300 bytes a sample).
      Measurement kept = m;
      kept.input_slopes = Eigen::MatrixXd();
      kept.input_correlation = Eigen::VectorXd();
      batch_series_.push_back(kept);
    }
    batch_last_stamp_ = stamp;
  } else {
    out.batch_full = true;
  }

  if (pdf_due) {
    out.pdf = PdfRequest{r.coefficients, static_cast<std::uint32_t>(r.index), stamp, {}, {}};
    if (!out.estimate.derived_names.empty()) {  // the rollover outputs' PDFs after them
      out.pdf->derived_names = out.estimate.derived_names;
      out.pdf->derived = derivedCoefficientsOf(out.estimate);
    }
  }
  return out;
}

double EstimatorRun::batchUntil() const {
  if (batch_series_.size() < static_cast<std::size_t>(config_.node.max_batch_samples)) {
    return std::numeric_limits<double>::infinity();
  }
  return batch_series_.back().time;
}

void EstimatorRun::saveTo(CheckpointSnapshot& s) const {
  Checkpoint& c = s.checkpoint;
  c.full = {full_.state(), full_.time(), full_.samples(), full_.workingPrior()};
  c.decimated = {decimated_.state(), decimated_.time(), decimated_.samples(),
                 decimated_.workingPrior()};
  c.coherence_disagreement = disagreement_;
  s.batch = batch_series_;
  c.batch_last_stamp = {batch_last_stamp_.sec, batch_last_stamp_.nsec};
}

void EstimatorRun::resumeFrom(const Checkpoint& c, const std::string& path) {
  const auto fits = [&](const FilterCheckpoint& f, const char* name) {
    const Eigen::MatrixXd& x = full_.state();
    if (f.x.rows() != x.rows() || f.x.cols() != x.cols()) {
      throw CheckpointError("checkpoint " + path + ": " + name + ".x is " +
                            std::to_string(f.x.rows()) + " x " + std::to_string(f.x.cols()) +
                            ", this configuration's filter is " + std::to_string(x.rows()) + " x " +
                            std::to_string(x.cols()));
    }
  };
  const auto working_fits = [&](const FilterCheckpoint& f, const char* name) {
    if (f.working.size() > 0 && (f.working.rows() != propagator_->parameterCount() ||
                                 f.working.cols() != full_.state().cols())) {
      throw CheckpointError("checkpoint " + path + ": " + name + ".working is " +
                            std::to_string(f.working.rows()) + " x " +
                            std::to_string(f.working.cols()) + ", this configuration's is " +
                            std::to_string(propagator_->parameterCount()) + " x " +
                            std::to_string(full_.state().cols()));
    }
  };
  working_fits(c.full, "full");
  working_fits(c.decimated, "decimated");
  fits(c.full, "full");
  fits(c.decimated, "decimated");
  const int parameters = propagator_->parameterCount();
  if (c.coherence_disagreement && c.coherence_disagreement->size() != parameters) {
    throw CheckpointError("checkpoint " + path + ": key 'coherence_disagreement' has " +
                          std::to_string(c.coherence_disagreement->size()) +
                          " values, this configuration estimates " + std::to_string(parameters) +
                          " parameters");
  }
  const int channels = static_cast<int>(propagator_->model().channelNames().size());
  for (std::size_t i = 0; i < c.batch_samples.size(); ++i) {
    const std::string problem = measurementProblem(c.batch_samples[i], channels);
    if (!problem.empty()) {
      throw CheckpointError("checkpoint " + path + ": key 'batch." + std::to_string(i) +
                            "': " + problem);
    }
  }
  full_.restore(c.full.x, c.full.time, c.full.samples, c.full.working);
  decimated_.restore(c.decimated.x, c.decimated.time, c.decimated.samples, c.decimated.working);
  disagreement_ = c.coherence_disagreement;
  batch_series_ = KeptSamples(c.batch_samples);
  batch_last_stamp_ = ros::Time(c.batch_last_stamp.sec, c.batch_last_stamp.nsec);
}

ParameterEstimate EstimatorRun::priorEstimate(const ros::Time& stamp) const {
  StepResult r;
  r.coefficients = propagator_->priorState().bottomRows(propagator_->parameterCount());
  r.mean = pcMean(r.coefficients);
  r.stddev = pcStddev(r.coefficients);
  r.health.mass_outside_support = Eigen::VectorXd::Zero(r.mean.size());
  return message(r, stamp, false);
}

BatchEstimate EstimatorRun::batch(bool road_complete) const {
  BatchEstimate out;
  const std::string method = toString(config_.node.batch_method);
  if (batch_series_.empty()) {
    out.summary = method + ": no samples since the last reset";
    return out;
  }
  if (!road_complete) {
    out.summary = method +
                  ": road samples since t = 0 were discarded (node.max_road_samples); "
                  "call ~reset to start a new record";
    return out;
  }
  const std::vector<double> alphas = config_.node.batch_method == BatchMethod::kEsMda
                                         ? config_.es_mda.alphas
                                         : std::vector<double>{1.0};
  const MeasurementSeries series = batch_series_.series();
  // estimate_offline's policy (runBatchEstimate); the node adds only what it
  // publishes: nothing for a non-finite result or a failed forecast.
  // The batch methods' own design when configured (collocation.batch_points,
  // pc.batch_tolerance_interactions), built per call on the filter's model.
  const std::shared_ptr<const PcPropagator> propagator =
      separateBatchDesign(config_)
          ? makePropagator(batchDesignConfig(config_), propagator_->modelPointer())
          : propagator_;
  const BatchOutcome o = runBatchEstimate(config_, *propagator, series, alphas);
  const BatchResult& b = o.result;
  const bool finite =
      b.finite && b.mean.allFinite() && b.stddev.allFinite() && b.coefficients.allFinite();
  std::ostringstream s;
  s << method << " (" << toString(config_.update) << ", " << b.iterations << " iterations) over "
    << batch_series_.size() << " samples";
  if (!finite || !b.forecast.ok) {
    s << ": failed (" << (finite ? "forecast failed" : "non-finite result")
      << (b.forecast.first_problem.empty() ? "" : ": " + b.forecast.first_problem)
      << "); nothing published";
    out.summary = s.str();
    return out;
  }
  ParameterEstimate& msg = out.estimate;
  msg.load_transfer_ratio = std::numeric_limits<double>::quiet_NaN();  // per sample only
  msg.header.stamp = batch_last_stamp_;
  msg.sample_index = static_cast<std::uint32_t>(batch_series_.size());
  msg.time = batch_series_.back().time;
  msg.method = method;
  msg.update_rule = toString(config_.update);
  setParameters(msg, propagator->mapping(), b.mean, b.stddev);
  setBasis(msg, propagator->basis());
  setCoefficients(msg, b.coefficients);
  setRolloverOutputs(msg, propagator->mapping(), propagator->basis(), b.coefficients);
  msg.nis = b.nis;
  msg.nis_channels = static_cast<std::uint32_t>(b.observations);
  msg.band_nested = true;
  msg.damping = b.damping;
  const PredictiveCheck& p = o.predictive;
  setPredictiveCheck(msg, p, "");  // its warning is among o.warnings
  if (p.outside) msg.warnings.pop_back();
  msg.healthy = o.healthy;
  msg.warnings.insert(msg.warnings.end(), o.warnings.begin(), o.warnings.end());
  if (p.available) {
    s << "; predictive check " << p.statistic << " in [" << p.lower << ", " << p.upper << "]"
      << (p.outside ? " FAILED" : "");
  }
  s << (msg.healthy ? "; healthy" : "; NOT healthy");
  s.precision(9);
  for (std::size_t i = 0; i < msg.names.size(); ++i) {
    s << (i ? ", " : ": ") << msg.names[i] << " " << msg.mean[i] << " +- " << msg.stddev[i];
  }
  out.summary = s.str();
  out.ok = true;
  return out;
}

}  // namespace pc_ekf
