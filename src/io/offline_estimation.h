// Runs one estimator over a whole measurement record (estimate_offline, the
// reproduction scripts and the tests share this path) and reports the JSON
// of docs/method.md §8.3 and the final PDFs; the per-sample rows go to a
// sink as they are made (samples.csv), never collected.
#pragma once

#include <Eigen/Dense>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "pc_ekf/filter/batch_update.h"
#include "pc_ekf/filter/measurement.h"
#include "pc_ekf/filter/pc_propagator.h"
#include "pc_ekf/health/predictive_check.h"
#include "pc_ekf/io/estimator_config.h"
#include "pc_ekf/io/offline_result.h"
#include "pc_ekf/io/road_free_stream.h"
#include "pc_ekf/model/mechanical_model.h"

namespace pc_ekf {

enum class EstimationMethod { kOneStep, kWholeSet, kEsMda, kEnkf, kGrid };
std::string toString(EstimationMethod m);
EstimationMethod estimationMethodFromString(const std::string& s);  // throws std::invalid_argument

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
// many seeds build it once per configuration. `samples` (may be null) gets
// every per-sample record in order: one per sample (one_step, enkf) or one
// for the whole record (es_mda, whole_set: its iterations; grid).
OfflineResult runOfflineEstimation(const EstimatorConfig& config, const MeasurementSeries& series,
                                   std::shared_ptr<const MechanicalModel> model,
                                   EstimationMethod method, std::uint64_t seed,
                                   const ProgressCallback& progress = {},
                                   const CoarseGridCache* grid_cache = nullptr,
                                   SampleSink* samples = nullptr);

// Road-free one-step (road.source none) on the raw readings: each sample is
// split into the model's inputs and outputs (RoadFreeStream) just before
// the filter takes it, as estimator_node does, and the inputs no filter
// reads again are forgotten: memory beyond the readings does not grow with
// the record. The same numbers as runOfflineEstimation on roadFreeRecord()'s
// split. Throws ConfigError for a sample the stream refuses (before the run).
// `interval` as RoadFreeStream's: a synthetic drive's sampling.interval(), a
// record's (the default) from its stamps.
OfflineResult runRoadFreeOneStep(const EstimatorConfig& config, const MeasurementSeries& readings,
                                 SampleSink* samples = nullptr,
                                 double interval = RoadFreeStream::kObservedInterval);
// The same run on readings that `readings` reads once, each to its
// argument in order: `count` of them, already checked (checkRoadFreeRecord
// finds nothing to drop or refuse), `inputs` RoadFreeStream::inputsFor them.
using ReadingPass = std::function<void(const std::function<void(const Measurement&)>&)>;
OfflineResult runRoadFreeOneStep(const EstimatorConfig& config, const ReadingPass& readings,
                                 std::size_t count, const std::vector<std::string>& inputs,
                                 SampleSink* samples, double interval);

std::string toJson(const OfflineResult& r);

class SamplesCsv;

// estimate_offline --out DIR: samples.csv written row by row while the run
// goes on (this is its sink), then pdfs.csv and, last, result.json (finish):
// a result.json marks a complete run. The directory is created with its
// parents and a previous run's result.json and pdfs.csv are removed.
// Throws std::runtime_error.
class OfflineOutputs : public SampleSink {
 public:
  explicit OfflineOutputs(const std::string& dir);
  ~OfflineOutputs() override;
  void begin(const SampleColumns& columns) override;
  void add(SampleRecord record) override;
  // samples.csv completed (only its header when no record came: the
  // columns of r), pdfs.csv and result.json written.
  void finish(const OfflineResult& r);

 private:
  std::string dir_;
  std::unique_ptr<SamplesCsv> samples_;
};

}  // namespace pc_ekf
