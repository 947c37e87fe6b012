#include "pc_ekf/io/offline_estimation.h"

#include <chrono>
#include <future>
#include <optional>
#include <stdexcept>

#include "pc_ekf/filter/batch_update.h"
#include "pc_ekf/filter/ensemble_kalman_filter.h"
#include "pc_ekf/filter/one_step_filter.h"
#include "pc_ekf/filter/reference_posterior.h"
#include "pc_ekf/io/road_free_stream.h"
#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/pc/in_parts.h"
#include "pc_ekf/pc/pdf_sampler.h"

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

// estimate_offline's one-step run assesses the support every this many samples.
constexpr int kSupportEvery = 10;

void summarise(const EstimatorConfig& c, const Eigen::VectorXd& mean, const Eigen::VectorXd& sd,
               OfflineResult* r) {
  r->parameters.clear();
  for (std::size_t i = 0; i < c.uncertain.size(); ++i) {
    const UncertainParameter& u = c.uncertain[i];
    const double scale = u.nominal * u.relative_range;
    r->parameters.push_back({u.name, mean[i], sd[i], (mean[i] - u.nominal) / scale, sd[i] / scale});
  }
}

// The final PDFs (makePdfSampler: shared draws or seed + i per parameter).
// The draws do not depend on the data, so the sampler is built on a second
// thread while the filter runs (same numbers whatever the timing).
using PdfSamplerFuture = std::shared_future<std::shared_ptr<const ParameterPdfSampler>>;
PdfSamplerFuture startPdfSampler(const EstimatorConfig& c, PolynomialBasis basis) {
  return std::async(std::launch::async, [&c, basis = std::move(basis)] {
    return makePdfSampler(c, basis, static_cast<int>(c.uncertain.size()), machineThreads());
  });
}
std::vector<Histogram> pcPdfs(const PdfSamplerFuture& sampler, const Eigen::MatrixXd& coeffs) {
  const std::shared_ptr<const ParameterPdfSampler> s = sampler.get();  // also when not finite
  if (!coeffs.allFinite()) return {};
  return s->histograms(coeffs, machineThreads());
}

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

// The multi-rate coherence check's filter (docs/method.md §5.2): the same
// filter on every k-th sample, on a thread of its own (it depends on nothing
// the full-rate filter computes) with a one-thread copy of the propagator
// (bitwise the same forecast). Empty when the record is too short.
using CoherenceFuture = std::future<std::optional<StepResult>>;
CoherenceFuture startCoherenceFilter(const EstimatorConfig& c, const MeasurementSeries& series,
                                     const PcPropagator& prop, const OneStepSettings& settings) {
  MeasurementSeries dec = decimate(series, c.health.coherence_decimation);
  if (!(dec.size() >= 1 && series.size() >= 2 * dec.size())) {
    std::promise<std::optional<StepResult>> none;
    none.set_value(std::nullopt);
    return none.get_future();
  }
  OneStepSettings coarse_settings = settings;  // it is asked for the mean and std only
  coarse_settings.health.support_every = 0;
  return std::async(std::launch::async, [dec = std::move(dec), prop = prop.withThreads(1),
                                         coarse_settings] {
    OneStepFilter coarse(prop, coarse_settings);
    StepResult d;
    for (const Measurement& m : dec) d = coarse.process(m);
    return std::optional<StepResult>(std::move(d));
  });
}

void runOneStep(const EstimatorConfig& c, const MeasurementSeries& series,
                std::shared_ptr<const MechanicalModel> model, OfflineResult* r) {
  // The PDF draws depend only on the basis: drawn while the propagator is built and the filter runs.
  const PdfSamplerFuture pdf_sampler = startPdfSampler(
      c, PolynomialBasis(ParameterMapping(*model, c.uncertain).germs(), c.pc_order, c.pc_truncation));
  const std::shared_ptr<const PcPropagator> prop = makePropagator(c, model);
  // The mass outside the support (a warning, docs/method.md §5.9) is
  // assessed at every 10th sample for its rate, and at the last one; it is
  // most of a sample's cost at n = 16. The coherence filter does without.
  OneStepSettings settings = makeOneStepSettings(c);
  settings.health.support_every = kSupportEvery;
  CoherenceFuture coherence = startCoherenceFilter(c, series, *prop, settings);
  OneStepFilter filter(prop, settings);
  StepResult last;
  int nested = 0, forecast_problems = 0;
  bool nonfinite = false;
  for (const Measurement& m : series) {
    last = filter.process(m);
    SampleRecord rec{last.index, last.time, last.mean, last.stddev, last.coefficients,
                     last.health.nis, last.health.nis_window_outside, last.health.band_nested,
                     last.health.healthy(), last.health.loo_error};
    r->records.push_back(rec);
    r->nis_window_violations += last.health.nis_window_outside;
    nested += last.health.band_nested;
    forecast_problems += last.forecast.invalid_points + last.forecast.nonfinite_points > 0;
    nonfinite = nonfinite || last.health.forecast_failed;
    r->damped_updates += last.damping < 1.0;
    r->reopened += last.reopened;
    const SafeguardRates& rates = last.health.rates;
    r->rate_window_violations += rates.gated.window.flagged || rates.damped.window.flagged ||
                                 rates.reopened.window.flagged || rates.support.window.flagged;
  }
  if (!series.empty() && last.health.mass_outside_support.size() == 0) filter.assessSupport(&last);
  r->safeguard_rates = last.health.rates;
  r->rejected_samples = filter.rejected();
  r->relinearized = last.restarts;
  // The leading channels the model gives as built (ForecastReport::loo_error).
  for (std::size_t i = 0; i < model->channelNames().size() && model->channelModelled(static_cast<int>(i)); ++i) {
    r->loo_channels.push_back(model->channelNames()[i]);
  }
  r->band_nested_fraction = series.empty() ? 1.0 : double(nested) / series.size();
  summarise(c, last.mean, last.stddev, r);
  r->pdfs = pcPdfs(pdf_sampler, last.coefficients);
  r->integrations = prop->integrations() + filter.horizonEvaluations();
  for (const auto& w : last.health.warnings()) r->warnings.push_back(w);
  if (r->rejected_samples) {
    r->warnings.push_back(std::to_string(r->rejected_samples) +
                          " samples not used (innovation gate or non-finite update)");
  }
  if (r->damped_updates) {
    r->warnings.push_back(std::to_string(r->damped_updates) +
                          " updates damped to keep the parameter means in their prior support");
  }
  if (r->reopened) r->warnings.push_back("uncertainty re-opened " + std::to_string(r->reopened) + " times");
  if (forecast_problems) {
    r->warnings.push_back(std::to_string(forecast_problems) +
                          " samples had collocation points outside the model's domain");
  }
  r->healthy = !nonfinite && last.health.healthy();

  // Multi-rate coherence (docs/method.md §5.2): the same filter on every k-th sample.
  r->coherence.decimation = c.health.coherence_decimation;
  r->coherence.threshold = c.health.coherence_threshold;
  if (const std::optional<StepResult> d = coherence.get()) {
    r->coherence.available = true;
    r->coherence.disagreement = coherenceDisagreement(last.mean, last.stddev, d->mean, d->stddev);
    r->coherence.flagged =
        !(r->coherence.disagreement.array() <= c.health.coherence_threshold).all();
    if (r->coherence.flagged) {
      r->warnings.push_back("multi-rate coherence check: full and decimated streams disagree");
      r->healthy = false;
    }
  }
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
              OfflineResult* r) {
  const PdfSamplerFuture pdf_sampler = startPdfSampler(c, prop->basis());
  const BatchOutcome o = runBatchEstimate(c, *prop, series, alphas);
  const BatchResult& b = o.result;
  SampleRecord rec{b.iterations, series.empty() ? 0.0 : series.back().time, b.mean, b.stddev,
                   b.coefficients, b.nis, false, true, b.finite && b.forecast.ok, {}};
  r->records.push_back(rec);
  summarise(c, b.mean, b.stddev, r);
  r->pdfs = pcPdfs(pdf_sampler, b.coefficients);
  r->integrations = prop->integrations() + long(b.iterations) * prop->design().pointCount();
  r->damped_updates = b.damping < 1.0;
  r->predictive = o.predictive;
  r->healthy = o.healthy;
  r->warnings.insert(r->warnings.end(), o.warnings.begin(), o.warnings.end());
}

void runEnkf(const EstimatorConfig& c, const MeasurementSeries& series,
             std::shared_ptr<const MechanicalModel> model, std::uint64_t seed,
             const ProgressCallback& progress, OfflineResult* r) {
  EnkfSettings s = makeEnkfSettings(c);
  s.seed = c.enkf.seed + seed;
  EnsembleKalmanFilter enkf(model, ParameterMapping(*model, c.uncertain), s);
  EnkfStep last;
  int frozen = 0;
  for (std::size_t i = 0; i < series.size(); ++i) {
    last = enkf.process(series[i]);
    frozen = std::max(frozen, last.inadmissible_members);
    r->records.push_back({last.index, last.time, last.mean, last.stddev, Eigen::MatrixXd(),
                          last.nis, false, true, last.finite, {}});
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
             const CoarseGridCache* cache, OfflineResult* r) {
  const ReferencePosterior p = computeReferencePosterior(
      *model, ParameterMapping(*model, c.uncertain), series, c.measurement.noise, c.integration,
      makeReferenceSettings(c), cache, progress);
  summarise(c, p.mean, p.stddev, r);
  r->records.push_back({static_cast<int>(series.size()), series.empty() ? 0.0 : series.back().time,
                        p.mean, p.stddev, Eigen::MatrixXd(), 0.0, false, true, true, {}});
  r->pdfs = p.marginals;
  r->integrations = p.simulations;
  r->modes = static_cast<int>(p.modes.size());
  r->border_mass = p.border_mass;
  if (p.modes.size() > 1) r->warnings.push_back("posterior has " + std::to_string(p.modes.size()) + " modes");
  if (p.border_mass > 1e-3) r->warnings.push_back("fine grid border mass above 1e-3");
  checkPrediction(c, series, *model, ParameterMapping(*model, c.uncertain), p.mean, r);
}

}  // namespace

BatchOutcome runBatchEstimate(const EstimatorConfig& c, const PcPropagator& propagator,
                              const MeasurementSeries& series, const std::vector<double>& alphas) {
  BatchOutcome o;
  o.result = batchUpdateRestarted(propagator, series, c.measurement.noise, c.update, alphas,
                                  c.safeguards.support, c.es_mda);
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
                                            c.health.nis_confidence);
    if (o.predictive.outside) {
      o.healthy = false;
      o.warnings.push_back(o.predictive.warning(propagator.model().channelNames(), series));
    }
  }
  return o;
}

OfflineResult runOfflineEstimation(const EstimatorConfig& c, const MeasurementSeries& series,
                                   std::shared_ptr<const MechanicalModel> model,
                                   EstimationMethod method, std::uint64_t seed,
                                   const ProgressCallback& progress,
                                   const CoarseGridCache* grid_cache) {
  // Possible with synthetic data whose truth.timing.drop_fraction lost every sample.
  if (series.empty()) throw std::invalid_argument(c.source + ": no samples to estimate from");
  const auto start = std::chrono::steady_clock::now();
  OfflineResult r;
  r.method = toString(method);
  r.update = toString(c.update);
  r.samples = static_cast<int>(series.size());
  switch (method) {
    case EstimationMethod::kOneStep: runOneStep(c, series, model, &r); break;
    case EstimationMethod::kWholeSet:
      runBatch(c, series, makePropagator(batchDesignConfig(c), model), {1.0}, &r);
      break;
    case EstimationMethod::kEsMda:
      runBatch(c, series, makePropagator(batchDesignConfig(c), model), c.es_mda.alphas, &r);
      break;
    case EstimationMethod::kEnkf: runEnkf(c, series, model, seed, progress, &r); break;
    case EstimationMethod::kGrid: runGrid(c, series, model, progress, grid_cache, &r); break;
  }
  const std::string caveat = roadFreeCaveat(c);
  if (!caveat.empty()) {
    r.healthy = false;
    r.warnings.push_back(caveat);
  }
  r.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

}  // namespace pc_ekf
