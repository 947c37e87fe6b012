// Road-free estimation on a stream (road.source none, docs/method.md §4.10):
// each sample's input readings (ModelType::roadFreeInputs) are appended to
// the inputs that drive the model's road-free form, and the other selected
// channels come out as the readings it predicts, with what they inherit from
// the inputs' noise. estimator_node feeds it sample by sample and
// estimate_offline feeds it a whole record the same way, so both give the
// same numbers.
#pragma once

#include <Eigen/Dense>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "pc_ekf/filter/measurement.h"
#include "pc_ekf/filter/serial_noise.h"
#include "pc_ekf/io/estimator_config.h"
#include "pc_ekf/io/standstill.h"
#include "pc_ekf/model/mechanical_model.h"
#include "pc_ekf/model/reading_inputs.h"

namespace pc_ekf {

class RoadFreeStream {
 public:
  // `inputs`: the model's required inputs then the optional ones used.
  // Throws ConfigError when the model cannot take them or cannot predict a
  // selected channel, or no selected channel is left to predict.
  // `interval`: the sample interval (s) the blended travel's noise is
  // reckoned at (measurement.travel_blend). A synthetic drive gives its own
  // (sampling.interval()); kObservedInterval (a record or a live stream)
  // takes it from the samples' stamps: the median of the intervals between
  // the first kIntervalSamples samples, renewed at 2, 4, ... samples (the
  // first sample's blended travel is its reading, so its noise is the
  // reading's). The config's sampling: is then never read.
  static constexpr double kObservedInterval = 0.0;
  static constexpr long kIntervalSamples = 128;
  RoadFreeStream(const EstimatorConfig& c, std::vector<std::string> inputs,
                 double interval = kObservedInterval);
  // The inputs of a record or stream: the required ones, and each optional
  // one that is selected (measurement.channels) and, when `record` is given,
  // read in it.
  static std::vector<std::string> inputsFor(const EstimatorConfig& c,
                                            const MeasurementSeries* record = nullptr);
  // The same for a record read as a stream: `read(channel)` whether the
  // record reads that model channel anywhere. A selected input of the
  // vehicle's horizontal motion (ModelType::RoadFreeInputs::zero_until_read:
  // speed, yaw rate) is an input whether read or not: 0 until first read.
  static std::vector<std::string> inputsFor(const EstimatorConfig& c,
                                            const std::function<bool(int)>& read);
  // "" or a warning naming the selected zero_until_read inputs that `read`
  // says the record never reads (taken as 0 throughout: a_y = 0).
  static std::string unreadMotionWarning(const EstimatorConfig& c,
                                         const std::function<bool(int)>& read);

  // Built on the inputs appended so far (they grow under it).
  const std::shared_ptr<const MechanicalModel>& model() const { return model_; }
  const std::vector<int>& outputChannels() const { return outputs_; }
  // The inputs as appended (a blended travel after its blend) and the std of
  // each one's noise there, absolute part (the relative part is scaled alike).
  const ReadingInputs& inputs() const { return *inputs_; }
  const Eigen::VectorXd& inputNoiseStd() const { return absolute_; }

  // Appends m's inputs and writes its outputs to `out`, with the covariance
  // they inherit from the noise of this sample's inputs
  // (Measurement::extra_covariance). Returns "" or why the sample was refused (an input not
  // read yet, a time not after the last); then nothing changes.
  std::string add(const Measurement& m, Measurement* out);
  // From now on add() also reckons each sample's Measurement::serial_variance
  // (for a batch method's posterior-predictive check; a little cost per sample).
  void trackSerialNoise() { serial_.emplace(); }
  // True while no sample has been taken and `m` lacks one of the inputs
  // (absent or NaN): add() refuses it, "not read yet", as there is nothing
  // to hold that input at. Such samples are dropped (estimator_node rejects
  // them; roadFreeRecord drops and counts them).
  bool waitingForInputs(const Measurement& m) const;
  // The inputs no estimator needs any more forgotten (ReadingInputs::forget):
  // `needed_from` the estimators' oldest time (EstimatorRun::oldestTime,
  // OneStepFilter::roadNeededFrom), `kept_until` the last sample a batch
  // over the record's first samples reads (-infinity: none). A stream that
  // runs for hours then holds a bounded tail, not the record.
  void forgetInputs(double needed_from, double kept_until) {
    inputs_->forget(needed_from, kept_until);
  }
  // measurement.standstill: samples taken as standing, and stops recognised.
  long standingSamples() const { return standstill_.standingSamples(); }
  long stops() const { return standstill_.stops(); }
  bool standing() const { return standstill_.standing(); }
  // The interval the blended travel's noise is reckoned at: the given one,
  // or the one observed so far (0 before two samples; no blend: 0).
  double interval() const { return interval_; }

 private:
  // measurement.travel_blend: u <- a (u_prev + trapezoid of v over dt) +
  // (1 - a) u, a = tau / (tau + dt), a complementary filter: the travel's
  // slow part (its sag) from its own reading, its fast part from the rate's
  // integral, with no lag on a travel and rate that agree.
  struct Blend {
    int u = -1, v = -1;  // input indices
    bool started = false;
    double u_blended = 0.0, t_last = 0.0, v_last = 0.0;
    double rho = 0.0;  // lag-1 correlation of the blended travel's noise
  };
  void blendTravel(Blend& b, double t, std::vector<double>* in) const;
  // The blended travels' noise (absolute_, relative_ and the inputs' lag-1
  // correlation) at interval dt, from their raw noise.
  void blendNoiseAt(double dt);
  // kObservedInterval: the sample at t taken; the interval renewed.
  void observeInterval(double t);
  void updateInputNoise();
  // filter.horizon.input_noise: state: this sample's inherited covariance
  // and its inputs' slopes and lag-1 correlations (Measurement::input_slopes);
  // `all_slopes`: every input's slopes, carried or not (reckonSerialNoise).
  void inputSlopes(std::size_t k, const Standstill::Decision& still, Measurement* o,
                   Eigen::MatrixXd* all_slopes = nullptr);
  // Sample k's inherited covariance and its inputs' slopes (a stop's: the
  // travels' over the readings averaged, no rate).
  void inheritedWithSlopes(std::size_t k, const Standstill::Decision& still,
                           Eigen::MatrixXd* covariance, Eigen::MatrixXd* slopes);
  // gyro_z read as an input (a_y = V psi'): its noise's share of a sample's
  // inherited covariance and input slopes, at the shrunk reading's error
  // (sqrt(s) of the raw std, at this sample and at the one before).
  void shrinkYawNoise(Eigen::MatrixXd* covariance, Eigen::MatrixXd* slopes) const;
  // o's serial_variance from its inputs' slopes (all inputs, model channel rows).
  void reckonSerialNoise(const Eigen::MatrixXd& slopes, Measurement* o);
  std::optional<SerialNoise> serial_;
  NoiseModel noise_;

  std::string source_;
  std::shared_ptr<ReadingInputs> inputs_;
  std::shared_ptr<const MechanicalModel> model_;
  std::vector<int> input_channels_;  // model channel per input
  std::vector<int> outputs_;          // ascending model channels
  Eigen::VectorXd absolute_, relative_;  // each input's noise (a blended travel's: after the blend)
  double blend_ = 0.0;                   // measurement.travel_blend (s)
  double interval_ = 0.0;                // the blend's noise is at this interval (s)
  bool observe_interval_ = false;        // interval_ still taken from the stamps
  double last_time_ = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> intervals_;        // observed so far (at most kIntervalSamples - 1)
  std::vector<Blend> blends_, blend_next_;
  int accel_z_ = -1;
  double accel_z_sum_ = 0.0;
  long accel_z_count_ = 0;
  long samples_ = 0;
  MechanicalModel::SampleInputNoise inherited_at_;
  // Standing: the travels' part (their raw noise, divided by the readings
  // averaged) and the other inputs' (rates: none).
  Standstill standstill_;
  std::vector<double> raw_;  // the sample's inputs as read (scratch)
  MechanicalModel::SampleInputNoise travels_at_, others_at_;
  Eigen::VectorXd raw_absolute_, raw_relative_;  // each input's noise before any blend
  std::vector<int> travel_inputs_, rate_inputs_;
  // filter.horizon.input_noise: state: the inputs whose noise the estimator
  // carries (those not also predicted: the gyro's reading is the previous
  // sample's measurement); whether the sample before was standing.
  std::vector<int> state_inputs_;
  bool was_standing_ = false;
  // The yaw rate gyro_z when it is an input (a_y = V psi', docs/method.md):
  // its reading r is shrunk to s r, s = max(0, 1 - sigma^2 / m), m the mean
  // square of its readings over kYawWindow (exponentially weighted), sigma its
  // noise std: the yaw rate's mean given the reading under a zero-mean prior
  // of the drive's own spread (empirical Bayes). Its error, of variance
  // s sigma^2, is then uncorrelated with the rate used, so a parameter that
  // scales a_y's effect is not pulled towards damping the gyro's noise (on a
  // straight drive, noise alone: s near 0). -1: gyro_z is not an input.
  static constexpr double kYawWindow = 0.5;  // s
  int yaw_ = -1;
  // zero_until_read inputs (their places) and whether each has been read.
  std::vector<int> zero_until_read_;
  std::vector<bool> motion_read_;
  double yaw_square_ = std::numeric_limits<double>::quiet_NaN(), yaw_time_ = 0.0;
  double yaw_shrink_ = 1.0, yaw_shrink_before_ = 1.0;
};

// A whole record through the stream: the model and the outputs. The samples
// before every input has been read (an IMU that starts after the suspension
// sensors) are dropped, as estimator_node drops them, and counted; the rest
// of the record is kept. Throws ConfigError naming any other sample a stream
// would refuse, or when no sample has every input.
struct RoadFreeRecord {
  std::shared_ptr<const MechanicalModel> model;
  MeasurementSeries outputs;
  std::size_t dropped = 0;  // samples before every input had been read
  std::string warning;      // what was dropped ("" when nothing)
};
// `interval` as RoadFreeStream's (a synthetic drive: sampling.interval()).
RoadFreeRecord roadFreeRecord(const EstimatorConfig& c, const MeasurementSeries& record,
                              double interval = RoadFreeStream::kObservedInterval);
// Throws the ConfigError roadFreeRecord would for the first sample a stream
// would refuse, without splitting anything (cheap; memory does not grow);
// returns the leading samples roadFreeRecord would drop (before every input
// had been read) and its warning.
struct RoadFreeCheck {
  std::size_t dropped = 0;
  std::string warning;
};
RoadFreeCheck checkRoadFreeRecord(const EstimatorConfig& c, const MeasurementSeries& record);
// checkRoadFreeRecord one sample at a time (a record read as a stream),
// with the record's `inputs` (RoadFreeStream::inputsFor). After a refusal
// later samples are not looked at; finish() throws it.
class RoadFreeChecker {
 public:
  RoadFreeChecker(const EstimatorConfig& c, const std::vector<std::string>& inputs);
  void add(const Measurement& m);
  RoadFreeCheck finish() const;

 private:
  const EstimatorConfig& c_;
  std::vector<int> channels_;
  ReadingInputs inputs_;
  std::vector<double> in_;
  std::vector<int> motion_;  // RoadFreeStream's zero_until_read_, motion_read_
  std::vector<bool> motion_read_;
  std::size_t k_ = 0;
  RoadFreeCheck check_;
  std::string first_problem_, refusal_;
};
// roadFreeRecord's warning for `dropped` leading samples ("" for none).
std::string droppedWarning(std::size_t dropped, const std::string& first_problem);
// That error's text for sample k (0-based) and the stream's reason.
std::string roadFreeRefusal(const EstimatorConfig& c, std::size_t k, const Measurement& m,
                            const std::string& problem);

// Why a road-free estimate of this config is not to be trusted, or empty.
// The full car's with accel_y is not: on its own synthetic drives the load's
// lateral position came out several std off while the health checks passed
// (scripts/road_free_study.py --full-car), so every result of it is reported
// not healthy, with this reason.
std::string roadFreeCaveat(const EstimatorConfig& c);

}  // namespace pc_ekf
