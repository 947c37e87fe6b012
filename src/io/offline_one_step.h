// One run of estimate_offline's one-step filter, fed sample by sample (a
// whole record's samples, or road-free ones as the stream splits them), and
// its ending: the running counts, the last sample and nothing else, so
// memory does not grow with the record.
#pragma once

#include <cstddef>
#include <memory>
#include <optional>

#include "pc_ekf/filter/one_step_filter.h"
#include "pc_ekf/io/estimator_config.h"
#include "pc_ekf/io/offline_parts.h"
#include "pc_ekf/io/offline_result.h"

namespace pc_ekf::offline {

class OneStepRun {
 public:
  // Starts the PDF draws, builds the propagator and the filter and gives
  // the sink its columns.
  OneStepRun(const EstimatorConfig& c, const std::shared_ptr<const MechanicalModel>& model,
             SampleSink* sink, OfflineResult* r);

  const PcPropagator& propagator() const { return *prop_; }
  const OneStepSettings& settings() const { return settings_; }
  const OneStepFilter& filter() const { return filter_; }

  void process(const Measurement& m);
  // After `samples` samples; `decimated`: the coherence filter's last
  // result (none: the record was too short for it).
  void finish(std::size_t samples, const std::optional<StepResult>& decimated);

 private:
  // last_'s record, with the load transfer ratio at its mean (model_).
  SampleRecord record() const;

  const EstimatorConfig& c_;
  SampleSink* sink_;
  OfflineResult* r_;
  const PdfSamplerFuture pdf_sampler_;
  const std::shared_ptr<const PcPropagator> prop_;
  const OneStepSettings settings_;
  OneStepFilter filter_;
  StepResult last_;
  int nested_ = 0, forecast_problems_ = 0;
  bool nonfinite_ = false;
  // The model, when it gives the load transfer ratio; null otherwise.
  std::shared_ptr<const MechanicalModel> model_;
};

// The multi-rate coherence check (docs/method.md §5.2): the same filter on
// every k-th sample (decimate()'s), when the record has enough of them, and
// its settings (asked for the mean and std only).
bool coherenceRuns(const EstimatorConfig& c, std::size_t samples);
OneStepSettings coherenceSettings(OneStepSettings s);

}  // namespace pc_ekf::offline
