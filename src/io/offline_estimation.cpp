#include "pc_ekf/io/offline_estimation.h"

#include <algorithm>
#include <chrono>
#include <future>
#include <limits>
#include <optional>
#include <stdexcept>

#include "pc_ekf/filter/batch_update.h"
#include "pc_ekf/filter/ensemble_kalman_filter.h"
#include "pc_ekf/filter/rollover_quantities.h"
#include "pc_ekf/reference/reference_posterior.h"
#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/io/offline_one_step.h"
#include "pc_ekf/io/offline_parts.h"
#include "pc_ekf/io/road_free_stream.h"

namespace pc_ekf {

std::string toString(EstimationMethod m) {
  switch (m) {
    case EstimationMethod::kOneStep: return "one_step";
    case EstimationMethod::kWholeSet: return "whole_set";
    case EstimationMethod::kEsMda: return "es_mda";
    case EstimationMethod::kEnkf: return "enkf";
    case EstimationMethod::kGrid: return "grid";
  }
  return "?";
}

EstimationMethod estimationMethodFromString(const std::string& s) {
  for (auto m : {EstimationMethod::kOneStep, EstimationMethod::kWholeSet, EstimationMethod::kEsMda,
                 EstimationMethod::kEnkf, EstimationMethod::kGrid}) {
    if (toString(m) == s) return m;
  }
  throw std::invalid_argument("method '" + s +
                              "' unknown, expected one_step, whole_set, es_mda, enkf or grid");
}

namespace {

using namespace offline;

Histogram sampleHistogram(const Eigen::VectorXd& v, int bins) {
  Histogram h;
  double lo = v.minCoeff(), hi = v.maxCoeff();
  if (!(hi > lo)) {
    lo -= 0.5;
    hi += 0.5;
  }
  h.edges = Eigen::VectorXd::LinSpaced(bins + 1, lo, hi);
  h.densities = Eigen::VectorXd::Zero(bins);
  const double width = (hi - lo) / bins;
  for (double x : v) {
    const int b = std::min(bins - 1, static_cast<int>((x - lo) / width));
    h.densities[b] += 1.0;
  }
  h.densities /= v.size() * width;
  return h;
}

// Over a whole record the coherence filter runs on a thread of its own (it
// depends on nothing the full-rate filter computes), reading every k-th
// sample in place, with a one-thread copy of the propagator (bitwise the
// same forecast). The series must outlive the future.
std::future<std::optional<StepResult>> startCoherenceFilter(const EstimatorConfig& c,
                                                            const MeasurementSeries& series,
                                                            const PcPropagator& prop,
                                                            const OneStepSettings& settings) {
  if (!coherenceRuns(c, series.size())) {
    std::promise<std::optional<StepResult>> none;
    none.set_value(std::nullopt);
    return none.get_future();
  }
  const std::size_t k = static_cast<std::size_t>(c.health.coherence_decimation);
  return std::async(std::launch::async, [&series, k, prop = prop.withThreads(1),
                                         s = coherenceSettings(settings)] {
    OneStepFilter coarse(prop, s);
    StepResult d;
    for (std::size_t i = k - 1; i < series.size(); i += k) d = coarse.process(series[i]);
    return std::optional<StepResult>(std::move(d));
  });
}

void runOneStep(const EstimatorConfig& c, const MeasurementSeries& series,
                std::shared_ptr<const MechanicalModel> model, SampleSink* sink, OfflineResult* r) {
  OneStepRun run(c, model, sink, r);
  auto coherence = startCoherenceFilter(c, series, run.propagator(), run.settings());
  for (const Measurement& m : series) run.process(m);
  run.finish(series.size(), coherence.get());
}

// Posterior-predictive check at the final mean (health.predictive_check).
void checkPrediction(const EstimatorConfig& c, const MeasurementSeries& series,
                     const MechanicalModel& model, const ParameterMapping& mapping,
                     const Eigen::VectorXd& mean, OfflineResult* r) {
  if (!c.health.predictive_check || series.empty() || !mean.allFinite()) return;
  r->predictive = posteriorPredictiveCheck(model, mapping.fullParameters(mean), series,
                                           c.measurement.noise, c.integration, mapping.count(),
                                           c.health.nis_confidence);
  if (r->predictive.outside) {
    r->healthy = false;
    r->warnings.push_back(r->predictive.warning(model.channelNames(), series));
  }
}

void runBatch(const EstimatorConfig& c, const MeasurementSeries& series,
              std::shared_ptr<const PcPropagator> prop, const std::vector<double>& alphas,
              SampleSink* sink, OfflineResult* r) {
  const PdfSamplerFuture pdf_sampler = startPdfSampler(c, prop->basis());
  prepareRolloverRule(prop->mapping(), prop->basis());
  if (sink) sink->begin(columnsOf(c, {}));
  const BatchOutcome o = runBatchEstimate(c, *prop, series, alphas);
  const BatchResult& b = o.result;
  give({b.iterations, series.empty() ? 0.0 : series.back().time, b.mean, b.stddev, b.coefficients,
        b.nis, false, true, b.finite && b.forecast.ok, {}},
       sink, r);
  summarise(c, b.mean, b.stddev, r);
  r->pdfs = pcPdfs(pdf_sampler, b.coefficients);
  summariseDerived(c, prop->mapping(), prop->basis(), b.coefficients, pdf_sampler, r);
  r->integrations = prop->integrations() + long(b.iterations) * prop->design().pointCount();
  r->damped_updates = b.damping < 1.0;
  r->predictive = o.predictive;
  r->healthy = o.healthy;
  r->warnings.insert(r->warnings.end(), o.warnings.begin(), o.warnings.end());
}

void runEnkf(const EstimatorConfig& c, const MeasurementSeries& series,
             std::shared_ptr<const MechanicalModel> model, std::uint64_t seed,
             const ProgressCallback& progress, SampleSink* sink, OfflineResult* r) {
  EnkfSettings s = makeEnkfSettings(c);
  s.seed = c.enkf.seed + seed;
  EnsembleKalmanFilter enkf(model, ParameterMapping(*model, c.uncertain), s);
  if (sink) sink->begin(columnsOf(c, {}));
  EnkfStep last;
  int frozen = 0;
  for (std::size_t i = 0; i < series.size(); ++i) {
    last = enkf.process(series[i]);
    frozen = std::max(frozen, last.inadmissible_members);
    give({last.index, last.time, last.mean, last.stddev, Eigen::MatrixXd(), last.nis, false, true,
          last.finite, {}},
         sink, r);
    if (progress && (i + 1) % 10 == 0) {
      progress("enkf: sample " + std::to_string(i + 1) + "/" + std::to_string(series.size()));
    }
  }
  summarise(c, last.mean, last.stddev, r);
  for (Eigen::Index i = 0; i < enkf.parameters().rows(); ++i) {
    r->pdfs.push_back(sampleHistogram(enkf.parameters().row(i).transpose(), c.pdf.bins));
  }
  r->integrations = enkf.integrations();
  r->healthy = last.finite;
  if (frozen) {
    r->warnings.push_back(std::to_string(frozen) + " ensemble members left the model's domain");
  }
  checkPrediction(c, series, *model, ParameterMapping(*model, c.uncertain), last.mean, r);
}

void runGrid(const EstimatorConfig& c, const MeasurementSeries& series,
             std::shared_ptr<const MechanicalModel> model, const ProgressCallback& progress,
             const CoarseGridCache* cache, SampleSink* sink, OfflineResult* r) {
  if (sink) sink->begin(columnsOf(c, {}));
  const ReferencePosterior p = computeReferencePosterior(
      *model, ParameterMapping(*model, c.uncertain), series, c.measurement.noise, c.integration,
      makeReferenceSettings(c), cache, progress);
  summarise(c, p.mean, p.stddev, r);
  give({static_cast<int>(series.size()), series.empty() ? 0.0 : series.back().time, p.mean,
        p.stddev, Eigen::MatrixXd(), 0.0, false, true, true, {}},
       sink, r);
  r->pdfs = p.marginals;
  r->integrations = p.simulations;
  r->modes = static_cast<int>(p.modes.size());
  r->border_mass = p.border_mass;
  if (p.modes.size() > 1) r->warnings.push_back("posterior has " + std::to_string(p.modes.size()) + " modes");
  if (p.border_mass > 1e-3) r->warnings.push_back("fine grid border mass above 1e-3");
  checkPrediction(c, series, *model, ParameterMapping(*model, c.uncertain), p.mean, r);
}

// Every run's end: the road-free caveat and the wall time since `start`.
void finishRun(const EstimatorConfig& c, std::chrono::steady_clock::time_point start,
               OfflineResult* r) {
  const std::string caveat = roadFreeCaveat(c);
  if (!caveat.empty()) {
    r->healthy = false;
    r->warnings.push_back(caveat);
  }
  r->wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

BatchOutcome runBatchEstimate(const EstimatorConfig& c, const PcPropagator& propagator,
                              const MeasurementSeries& series, const std::vector<double>& alphas) {
  BatchOutcome o;
  BatchRestarts restarts = c.es_mda;
  restarts.nuisance = BatchNuisance::from(c.safeguards.horizon);
  o.result = batchUpdateRestarted(propagator, series, c.measurement.noise, c.update, alphas,
                                  c.safeguards.support, restarts);
  const BatchResult& b = o.result;
  o.healthy = b.finite && b.forecast.ok;
  if (!b.forecast.first_problem.empty()) o.warnings.push_back(b.forecast.first_problem);
  if (c.es_mda.local_covariance && o.healthy && !b.local_covariance) {
    // Informational: the passes' covariance is reported instead.
    o.warnings.push_back(
        "filter.es_mda.covariance local not applied (a run at the mean failed or the "
        "information was not positive definite): the passes' covariance is reported");
  }
  if (b.damping < 1.0) {
    o.healthy = false;
    o.warnings.push_back(
        "update damped to keep the parameter means in their prior support "
        "(model error, or a parameter that should be declared uncertain)");
  }
  if (c.health.predictive_check && !series.empty() && b.mean.allFinite()) {
    const ParameterMapping& map = propagator.mapping();
    // At the mode when the method found it: on a curved ridge the mean lies
    // off the ridge (local_covariance.h).
    const Eigen::VectorXd& at = b.mode.size() > 0 ? b.mode : b.mean;
    o.predictive = posteriorPredictiveCheck(propagator.model(), map.fullParameters(at), series,
                                            c.measurement.noise, c.integration, map.count(),
                                            c.health.nis_confidence, restarts.nuisance);
    if (o.predictive.outside) {
      o.healthy = false;
      o.warnings.push_back(o.predictive.warning(propagator.model().channelNames(), series));
    }
  }
  return o;
}

OfflineResult runRoadFreeOneStep(const EstimatorConfig& c, const MeasurementSeries& readings,
                                 SampleSink* samples, double interval) {
  if (readings.empty()) throw std::invalid_argument(c.source + ": no samples to estimate from");
  checkRoadFreeRecord(c, readings);  // a refused sample fails now, not hours in
  return runRoadFreeOneStep(
      c,
      [&readings](const std::function<void(const Measurement&)>& take) {
        for (const Measurement& m : readings) take(m);
      },
      readings.size(), RoadFreeStream::inputsFor(c, &readings), samples, interval);
}

OfflineResult runRoadFreeOneStep(const EstimatorConfig& c, const ReadingPass& readings,
                                 std::size_t count, const std::vector<std::string>& inputs,
                                 SampleSink* samples, double interval) {
  if (count == 0) throw std::invalid_argument(c.source + ": no samples to estimate from");
  const auto start = std::chrono::steady_clock::now();
  OfflineResult r;
  r.method = toString(EstimationMethod::kOneStep);
  r.update = toString(c.update);
  r.samples = static_cast<int>(count);
  RoadFreeStream stream(c, inputs, interval);
  OneStepRun run(c, stream.model(), samples, &r);
  // The coherence filter in step with the stream: the inputs it reads are
  // appended, and forgotten once neither filter needs them.
  const std::size_t k = static_cast<std::size_t>(c.health.coherence_decimation);
  std::optional<OneStepFilter> coarse;
  if (coherenceRuns(c, count)) {
    coarse.emplace(run.propagator().withThreads(1), coherenceSettings(run.settings()));
  }
  std::optional<StepResult> decimated;
  Measurement outputs;
  std::size_t i = 0;
  readings([&](const Measurement& m) {
    const std::string problem = stream.add(m, &outputs);
    if (!problem.empty()) throw ConfigError(roadFreeRefusal(c, i, m, problem));
    run.process(outputs);
    if (coarse && (i + 1) % k == 0) decimated = coarse->process(outputs);
    const double needed = run.filter().roadNeededFrom();
    stream.forgetInputs(coarse ? std::min(needed, coarse->roadNeededFrom()) : needed,
                        -std::numeric_limits<double>::infinity());
    ++i;
  });
  if (i != count) {
    throw std::logic_error(c.source + ": " + std::to_string(i) + " samples read, " +
                           std::to_string(count) + " expected");
  }
  run.finish(count, decimated);
  finishRun(c, start, &r);
  return r;
}

OfflineResult runOfflineEstimation(const EstimatorConfig& c, const MeasurementSeries& series,
                                   std::shared_ptr<const MechanicalModel> model,
                                   EstimationMethod method, std::uint64_t seed,
                                   const ProgressCallback& progress,
                                   const CoarseGridCache* grid_cache, SampleSink* samples) {
  // Possible with synthetic data whose truth.timing.drop_fraction lost every sample.
  if (series.empty()) throw std::invalid_argument(c.source + ": no samples to estimate from");
  const auto start = std::chrono::steady_clock::now();
  OfflineResult r;
  r.method = toString(method);
  r.update = toString(c.update);
  r.samples = static_cast<int>(series.size());
  switch (method) {
    case EstimationMethod::kOneStep: runOneStep(c, series, model, samples, &r); break;
    case EstimationMethod::kWholeSet:
      runBatch(c, series, makePropagator(batchDesignConfig(c), model), {1.0}, samples, &r);
      break;
    case EstimationMethod::kEsMda:
      runBatch(c, series, makePropagator(batchDesignConfig(c), model), c.es_mda.alphas, samples,
               &r);
      break;
    case EstimationMethod::kEnkf: runEnkf(c, series, model, seed, progress, samples, &r); break;
    case EstimationMethod::kGrid:
      runGrid(c, series, model, progress, grid_cache, samples, &r);
      break;
  }
  finishRun(c, start, &r);
  return r;
}

}  // namespace pc_ekf
