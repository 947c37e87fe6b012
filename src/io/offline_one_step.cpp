#include "pc_ekf/io/offline_one_step.h"

#include <stdexcept>

#include "pc_ekf/filter/health.h"
#include "pc_ekf/filter/rollover_quantities.h"
#include "pc_ekf/io/estimation_setup.h"

namespace pc_ekf::offline {
namespace {

// estimate_offline's one-step run assesses the support every this many samples.
constexpr int kSupportEvery = 10;

SampleRecord recordOf(const StepResult& s) {
  return {s.index, s.time, s.mean, s.stddev, s.coefficients, s.health.nis,
          s.health.nis_window_outside, s.health.band_nested, s.health.healthy(),
          s.health.loo_error};
}

// The mass outside the support (a warning, docs/method.md §5.9) is
// assessed at every 10th sample for its rate, and at the last one; it is
// most of a sample's cost at n = 16. The coherence filter does without.
OneStepSettings supportEvery(OneStepSettings s) {
  s.health.support_every = kSupportEvery;
  return s;
}

}  // namespace

bool coherenceRuns(const EstimatorConfig& c, std::size_t samples) {
  const std::size_t k = static_cast<std::size_t>(c.health.coherence_decimation);
  if (k < 1) throw std::invalid_argument("decimation must be >= 1");
  return samples / k >= 1 && samples >= 2 * (samples / k);
}

OneStepSettings coherenceSettings(OneStepSettings s) {
  s.health.support_every = 0;
  return s;
}

OneStepRun::OneStepRun(const EstimatorConfig& c,
                       const std::shared_ptr<const MechanicalModel>& model, SampleSink* sink,
                       OfflineResult* r)
    : c_(c),
      sink_(sink),
      r_(r),
      // The PDF draws depend only on the basis: drawn while the propagator
      // is built and the filter runs.
      pdf_sampler_(startPdfSampler(c, PolynomialBasis(ParameterMapping(*model, c.uncertain).germs(),
                                                      c.pc_order, c.pc_truncation))),
      prop_(makePropagator(c, model)),
      settings_(supportEvery(makeOneStepSettings(c))),
      filter_(prop_, settings_) {
  prepareRolloverRule(prop_->mapping(), prop_->basis());  // made while the filter runs
  // The leading channels the model gives as built (ForecastReport::loo_error).
  for (std::size_t i = 0;
       i < model->channelNames().size() && model->channelModelled(static_cast<int>(i)); ++i) {
    r->loo_channels.push_back(model->channelNames()[i]);
  }
  r->load_transfer_ratio = model->hasLoadTransferRatio();
  if (r->load_transfer_ratio) model_ = model;
  SampleColumns columns = columnsOf(c, r->loo_channels);
  columns.load_transfer_ratio = r->load_transfer_ratio;
  if (sink_) sink_->begin(columns);
}

SampleRecord OneStepRun::record() const {
  SampleRecord s = recordOf(last_);
  if (model_ && last_.mean.size() > 0 && last_.mean.allFinite()) {
    const Eigen::VectorXd full = prop_->mapping().fullParameters(last_.mean);
    s.load_transfer_ratio = model_->loadTransferRatio(full, last_.time);
  }
  return s;
}

void OneStepRun::process(const Measurement& m) {
  last_ = filter_.process(m);
  if (sink_) sink_->add(record());
  r_->nis_window_violations += last_.health.nis_window_outside;
  nested_ += last_.health.band_nested;
  forecast_problems_ += last_.forecast.invalid_points + last_.forecast.nonfinite_points > 0;
  nonfinite_ = nonfinite_ || last_.health.forecast_failed;
  r_->damped_updates += last_.damping < 1.0;
  r_->reopened += last_.reopened;
  if (last_.load_reset) {
    LoadChangeEvent e{last_.load_change_time, last_.time, {}};
    for (std::size_t i = 0; i < c_.uncertain.size(); ++i) {
      if (c_.uncertain[i].name.rfind("added_mass", 0) != 0) continue;
      ParameterSummary p;
      p.name = c_.uncertain[i].name;
      p.mean = last_.mean[static_cast<Eigen::Index>(i)];
      p.stddev = last_.stddev[static_cast<Eigen::Index>(i)];
      e.load.push_back(p);
    }
    r_->load_changes.push_back(std::move(e));
  }
  const SafeguardRates& rates = last_.health.rates;
  r_->rate_window_violations += rates.gated.window.flagged || rates.damped.window.flagged ||
                                rates.reopened.window.flagged || rates.support.window.flagged;
}

void OneStepRun::finish(std::size_t samples, const std::optional<StepResult>& decimated) {
  OfflineResult* r = r_;
  if (samples > 0 && last_.health.mass_outside_support.size() == 0) filter_.assessSupport(&last_);
  r->safeguard_rates = last_.health.rates;
  r->rejected_samples = filter_.rejected();
  r->relinearized = last_.restarts;
  r->load_tracking = c_.safeguards.reopen.mode == ReopenMode::kLoad;
  r->clock_offset = last_.clock_offset;
  r->clock_offset_std = last_.clock_offset_std;
  r->nuisance = last_.nuisance;
  r->last_record = record();
  r->band_nested_fraction = samples == 0 ? 1.0 : double(nested_) / samples;
  summarise(c_, last_.mean, last_.stddev, r);
  r->pdfs = pcPdfs(pdf_sampler_, last_.coefficients);
  summariseDerived(c_, prop_->mapping(), prop_->basis(), last_.coefficients, pdf_sampler_, r);
  r->integrations = prop_->integrations() + filter_.horizonEvaluations();
  for (const auto& w : last_.health.warnings()) r->warnings.push_back(w);
  if (r->rejected_samples) {
    r->warnings.push_back(std::to_string(r->rejected_samples) +
                          " samples not used (innovation gate or non-finite update)");
  }
  if (r->damped_updates) {
    r->warnings.push_back(std::to_string(r->damped_updates) +
                          " updates damped to keep the parameter means in their prior support");
  }
  if (r->reopened) {
    r->warnings.push_back("uncertainty re-opened " + std::to_string(r->reopened) + " times");
  }
  if (forecast_problems_) {
    r->warnings.push_back(std::to_string(forecast_problems_) +
                          " samples had collocation points outside the model's domain");
  }
  r->healthy = !nonfinite_ && last_.health.healthy();

  // Multi-rate coherence (docs/method.md §5.2): the same filter on every k-th sample.
  r->coherence.decimation = c_.health.coherence_decimation;
  r->coherence.threshold = c_.health.coherence_threshold;
  if (decimated) {
    r->coherence.available = true;
    r->coherence.disagreement =
        coherenceDisagreement(last_.mean, last_.stddev, decimated->mean, decimated->stddev);
    r->coherence.flagged =
        !(r->coherence.disagreement.array() <= c_.health.coherence_threshold).all();
    if (r->coherence.flagged) {
      r->warnings.push_back("multi-rate coherence check: full and decimated streams disagree");
      r->healthy = false;
    }
  }
}

}  // namespace pc_ekf::offline
