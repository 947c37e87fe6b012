// Builds the core objects (model, road, PC design, propagator, filter
// settings, data) from one EstimatorConfig: the same path for the node and
// the CLIs.
#pragma once

#include <memory>

#include "pc_ekf/filter/ensemble_kalman_filter.h"
#include "pc_ekf/filter/one_step_filter.h"
#include "pc_ekf/filter/pc_propagator.h"
#include "pc_ekf/reference/reference_posterior.h"
#include "pc_ekf/filter/synthetic_data.h"
#include "pc_ekf/io/estimator_config.h"
#include "pc_ekf/pc/pdf_sampler.h"
#include "pc_ekf/io/measurement_csv.h"

namespace pc_ekf {

// Road of the config; `sampled` replaces it when given (road from a bag/topic).
// Throws ConfigError (series file unreadable) or std::invalid_argument
// (source topic without samples).
// Throws ConfigError also for a road source the model's contacts cannot take
// (sine and course are two-contact roads).
std::shared_ptr<const ContactRoad> makeRoad(const EstimatorConfig& c,
                                            std::shared_ptr<const ContactRoad> sampled = nullptr);
// The truth's model (its vehicle, readings as configured) on makeTruthRoad.
std::shared_ptr<const MechanicalModel> truthOnItsRoad(const EstimatorConfig& c);
// The road the truth of a synthetic drive drives on: truth.road, else the
// config's road (ConfigError when that is none).
std::shared_ptr<const ContactRoad> makeTruthRoad(const EstimatorConfig& c);
// The config's model type with its parameters on `road`.
std::shared_ptr<const MechanicalModel> makeModel(const EstimatorConfig& c,
                                                 std::shared_ptr<const ContactRoad> road);
// Throws ConfigError naming collocation.points for a degenerate design.
// c with the batch methods' design (pc.batch_tolerance_interactions,
// collocation.batch_points) in place of the one-step filter's: ES-MDA,
// whole-set over the whole prior width.
EstimatorConfig batchDesignConfig(EstimatorConfig c);
// Whether the batch methods' design differs from the one-step filter's.
bool separateBatchDesign(const EstimatorConfig& c);

std::shared_ptr<const PcPropagator> makePropagator(const EstimatorConfig& c,
                                                   std::shared_ptr<const MechanicalModel> model);
// The filters' settings: their own keys (filter.support, .drift, .reopen,
// .relinearize, filter.enkf, health:) as parsed, with what they share with the
// other sections (R: measurement.noise, the integrator, the seeds and threads).
OneStepSettings makeOneStepSettings(const EstimatorConfig& c);
EnkfSettings makeEnkfSettings(const EstimatorConfig& c);
// The PDF sampler of pdf: (draws, bins, seed; shared or per-parameter draws)
// for `parameters` rows in `basis`, drawn on `threads` threads (the same
// draws for any count).
std::shared_ptr<const ParameterPdfSampler> makePdfSampler(const EstimatorConfig& c,
                                                          const PolynomialBasis& basis,
                                                          int parameters, int threads = 1);
// The grid: section (and pdf.bins) as settings of the exact posterior.
ReferencePosteriorSettings makeReferenceSettings(const EstimatorConfig& c);
std::vector<int> channelIndices(const EstimatorConfig& c);
// "" or why a record's accel_z does not read as measurement.zero says: with
// rest it should average about 0 (deviations from rest), with tare about +g
// (a raw IMU, REP 145). A mean beyond g/2 of that is gravity left in, taken
// out, or a z axis pointing down.
std::string zeroConventionProblem(const EstimatorConfig& c, const MeasurementSeries& series);
// The same summed one sample at a time (a record read as a stream).
class ZeroConventionSum {
 public:
  explicit ZeroConventionSum(const EstimatorConfig& c);
  void add(const Measurement& m);
  std::string problem() const;

 private:
  const EstimatorConfig& c_;
  int channel_;
  double sum_ = 0.0;
  long count_ = 0;
};

// `c` with the model parameters `names` declared uncertain as well: nominal
// the configured vehicle's value, relative_range `range`, a Beta(2,2) germ,
// the truth at germ coordinate `xi_truth` (how the scaling benchmarks and
// tests grow n). Throws ConfigError for a name the model does not have.
// ConfigError when a tolerance's support leaves the model's physical domain.
void checkToleranceDomain(const EstimatorConfig& c, const MechanicalModel& model,
                          const ParameterMapping& mapping);

EstimatorConfig withUncertain(EstimatorConfig c, const std::vector<std::string>& names,
                              double range, double xi_truth);

// Synthetic data of the config (truth section, sampling, noise) with `seed`.
// `model` is the estimator's; truth.vehicle gives the truth its own model on
// the same road.
MeasurementSeries synthesizeFromConfig(const EstimatorConfig& c, const MechanicalModel& model,
                                       std::uint64_t seed);
// The model the truth is simulated with: `model` itself, or the config's
// model type with truth.vehicle applied on model's road (which must outlive
// the result). Throws ConfigError when the model has no road to share.
std::shared_ptr<const MechanicalModel> truthModel(const EstimatorConfig& c,
                                                  const MechanicalModel& model);
// Full parameter vector of the truth model at t = 0 (truth.xi).
Eigen::VectorXd truthParameters(const EstimatorConfig& c, const MechanicalModel& model);
// Germ point of the truth at time t (truth.xi, then truth.schedule).
Eigen::VectorXd truthXiAt(const EstimatorConfig& c, double t);
// Stamps of the synthetic samples (jittered, without the dropped ones): they do
// not depend on the noise seed.
std::vector<double> syntheticSampleTimes(const EstimatorConfig& c);
// Settings synthesizeFromConfig passes to synthesizeMeasurements; `truth` is
// truthModel(c, ...) (the schedule's parameter vectors are its).
SyntheticDataSettings syntheticSettings(const EstimatorConfig& c, const MechanicalModel& truth,
                                        std::uint64_t seed);

// `road` sampled at `rate` Hz from t = 0 until the first time >= t_end, under
// every contact: the road stream a bag or a live vehicle would carry.
ContactSeries sampleContactRoad(const ContactRoad& road, double t_end, double rate);

}  // namespace pc_ekf
