// The estimation state of one run of estimator_node (from start or ~reset to
// the next): the one-step filter on every sample, a second one-step filter on
// every k-th sample for the multi-rate coherence check (docs/method.md §5.2), and the
// samples kept for the batch update (~estimate_batch). Messages out, core in.
#pragma once

#include <pc_ekf/ParameterEstimate.h>
#include <pc_ekf/ParameterPdf.h>
#include <ros/time.h>

#include <memory>
#include <optional>
#include <string>

#include "pc_ekf/filter/kept_samples.h"
#include "pc_ekf/filter/one_step_filter.h"
#include "pc_ekf/filter/rollover_quantities.h"
#include "pc_ekf/io/checkpoint.h"
#include "pc_ekf/io/estimator_config.h"
#include "pc_ekf/pc/pdf_sampler.h"
#include "pc_ekf/ros/estimator_run_pdfs.h"
#include "pc_ekf/ros/estimator_run_road.h"

namespace pc_ekf {

struct SampleEstimate {
  ParameterEstimate estimate;
  // parameter_pdf due (node.pdf_every): its coefficients, for PdfWorker.
  std::optional<PdfRequest> pdf;
  // The update produced NaN/Inf: the filter went back to its state before the
  // sample and the message carries that state with non_finite = true.
  bool non_finite = false;
  bool coherence_non_finite = false;  // the same for the decimated filter
  bool batch_full = false;            // not kept for ~estimate_batch (max_batch_samples)
  HealthStatus health;
};

struct BatchEstimate {
  bool ok = false;
  std::string summary;  // the ~estimate_batch reply
  ParameterEstimate estimate;
};

class EstimatorRun {
 public:
  // `pdfs` false: no parameter_pdf messages. `topic_road`: the road of
  // `propagator`'s model when it grows from road messages (a deferred re-run
  // then reads copies of it, RoadSnapshots).
  EstimatorRun(const EstimatorConfig& config, std::shared_ptr<const PcPropagator> propagator,
               bool pdfs, std::shared_ptr<const SampledRoad> topic_road = nullptr);

  // Forecast to m.time and update; m.time must not be before time().
  SampleEstimate process(const Measurement& m, const ros::Time& stamp);
  // ES-MDA or whole-set (config node.batch_method) over the kept samples.
  // `road_complete` false: the road since t = 0 is gone, refuse.
  BatchEstimate batch(bool road_complete) const;
  // The prior as a message (sample_index 0).
  ParameterEstimate priorEstimate(const ros::Time& stamp) const;

  int samples() const { return full_.samples(); }
  double time() const { return full_.time(); }
  // Earliest time a filter will integrate from (road before it is not needed
  // by the one-step filters).
  double oldestTime() const;
  std::size_t batchSamples() const { return batch_series_.size(); }
  // The last sample time batch() reads: infinity while the batch still
  // keeps every sample (the road-free inputs up to it must stay).
  double batchUntil() const;
  // Deferred re-run of the full filter: swap after this sample (0 = none).
  int pendingSwap() const { return pending_swap_; }
  int lateSwaps() const { return full_.lateSwaps(); }

  // The run's state into a checkpoint: both filters, the last coherence
  // comparison and the kept batch samples (the node adds origin and counters).
  // Cheap enough for the sample callback: the samples are shared, not copied.
  void saveTo(CheckpointSnapshot& s) const;
  // Continues a checkpointed run of the same configuration (the health
  // monitors' NIS windows restart). Throws CheckpointError naming `path`
  // when the state does not fit this run's filters.
  void resumeFrom(const Checkpoint& c, const std::string& path);

 private:
  // latest_derived: the derived quantities of the latest projection (project),
  // else projected from r.
  ParameterEstimate message(const StepResult& r, const ros::Time& stamp,
                            bool latest_derived = true) const;
  // The derived quantities (rollover outputs) of r projected again when due:
  // every node.derived_every samples, at a PDF, a load change or a
  // re-linearisation, and while none is made (a projection over the sparse
  // grid costs milliseconds, the filter's update less than one).
  void project(const StepResult& r, bool pdf_due);

  EstimatorConfig config_;
  std::shared_ptr<const PcPropagator> propagator_;
  bool pdfs_;
  std::shared_ptr<RoadSnapshots> rerun_road_;  // topic road: the deferred re-runs' copies
  OneStepFilter full_;
  OneStepFilter decimated_;
  std::optional<Eigen::VectorXd> disagreement_;  // last multi-rate comparison
  DerivedExpansions derived_;  // the latest projection, made at sample derived_index_
  int derived_index_ = -1;     // -1: none yet
  KeptSamples batch_series_;
  ros::Time batch_last_stamp_;
  int pending_swap_ = 0;
};

// Replaces every non-finite number of a message by 0 (documented in the
// README: only after a non-finite update, which the flags report).
void zeroNonFinite(ParameterEstimate& msg);

}  // namespace pc_ekf
