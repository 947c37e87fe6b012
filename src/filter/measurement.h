// Measurements as the estimators consume them: one sample per time, any
// subset of the model's channels (docs/method.md §1.6).
#pragma once

#include <Eigen/Dense>
#include <vector>

namespace pc_ekf {

struct Measurement {
  double time = 0.0;           // s since the time origin (vehicle at rest at t = 0)
  std::vector<int> channels;   // indices into the model's channelNames(), ascending
  Eigen::VectorXd values;      // one per entry of `channels`
  // Optional, per value: the sensor's own variance for this reading (an IMU
  // message's covariance, docs/nodes.md); NaN or an empty vector = none (the
  // NoiseModel's rule). Where given, R_jj = variance + (r_relative_c z_j)^2.
  // (Initialised here so that Measurement{t, channels, values} stays warning-free.)
  Eigen::VectorXd variances{};
  // Optional (values x values): added to R, what the readings inherit from
  // the noise of readings used as inputs (road-free, errors in variables).
  // Off its diagonal it correlates this sample's readings (NoiseWhitening).
  Eigen::MatrixXd extra_covariance{};
  // Optional (values x 2 inputs), for an estimator that carries the inputs'
  // noise as states of its own (filter.horizon.input_noise: state): each
  // input's change of the readings by its noise at this sample (the first
  // half of the columns) and at the one before (the second), the derivative
  // times that noise's std; extra_covariance includes them all. The
  // standardised noise of input i at this sample correlates with that at the
  // one before by input_correlation[i].
  Eigen::MatrixXd input_slopes{};
  Eigen::VectorXd input_correlation{};
  // The sample's share of the whitened residuals' sum of squares' variance
  // beyond 2 per entry, from noise it shares with the samples before it
  // (road-free inputs: filter/serial_noise.h); 0 when none or not reckoned.
  double serial_variance = 0.0;
  // A recognised stop's sample (road-free, measurement.standstill): the
  // vehicle values' walk over the interval it ends is filter.drift alone.
  bool standing = false;
};

// What input slopes s and correlations rho add to a sample's R (the noise
// of each input at the sample and at the one before, standardised, with
// correlation rho_i between them): sum_i a_i a_i' + b_i b_i' + rho_i (a_i b_i'
// + b_i a_i'), a_i and b_i the columns i and inputs + i of s.
Eigen::MatrixXd inputSlopesCovariance(const Eigen::MatrixXd& slopes, const Eigen::VectorXd& rho);

using MeasurementSeries = std::vector<Measurement>;

// Filter noise R (diagonal), by one of two rules:
//  paper  (paper eq. 50-54): R_jj = max(r_floor, (r_relative * z_obs,j)^2)
//  sensor (real sensors):   R_jj = std_c^2 + (r_relative * z_obs,j)^2, std_c the
//         absolute noise of the reading's channel c (datasheet noise floor).
// Both scale with the observation, not the prediction: R is then fixed by the
// data, the same for every method, collocation point and iteration, and the
// exact posterior stays a weighted least-squares problem. The sensor rule's
// floor keeps R from collapsing at zero readings.
enum class NoiseRule { kPaper, kSensor };

struct NoiseModel {
  NoiseModel() = default;
  NoiseModel(double relative, double floor) : r_relative(relative), r_floor(floor) {}
  double r_relative = 0.01;
  double r_floor = 1e-12;         // paper rule
  NoiseRule rule = NoiseRule::kPaper;
  Eigen::VectorXd channel_std;    // sensor rule: one per model channel
  // One r_relative per model channel (empty: r_relative for every channel):
  // an IMU's noise does not grow with the 9.81 of gravity in its reading.
  Eigen::VectorXd channel_relative;
  // R's diagonal (extra_covariance's included).
  Eigen::VectorXd variances(const Measurement& m) const;
  // Over a whole record, stacked in sample order.
  Eigen::VectorXd stackedVariances(const std::vector<Measurement>& series) const;
};

// One sample's R as the estimators take it. When its readings' noise is
// correlated between channels (extra_covariance off its diagonal), R = L L'
// (Cholesky) and whiten() replaces rows (values, or predictions, one row per
// reading) by L^-1 rows: whitened, the readings have independent unit noise,
// and a Kalman update, NIS or likelihood on them equals the one with the full
// R; variances() is then 1. Otherwise (inactive) whiten() leaves the rows
// alone and variances() is R's diagonal, noise.variances(m).
class NoiseWhitening {
 public:
  NoiseWhitening(const NoiseModel& noise, const Measurement& m);
  bool active() const { return active_; }
  const Eigen::VectorXd& variances() const { return variances_; }
  template <class Rows>
  void whiten(const Eigen::MatrixBase<Rows>& rows) const {
    if (active_) l_.triangularView<Eigen::Lower>().solveInPlace(rows);
  }

 private:
  Eigen::MatrixXd l_;
  Eigen::VectorXd variances_;
  bool active_ = false;
};

// The series with only the channels in `keep` (ascending model indices);
// samples left with none stay (as samples without readings).
MeasurementSeries onlyChannels(const MeasurementSeries& series, const std::vector<int>& keep);
Measurement onlyChannels(const Measurement& m, const std::vector<int>& keep);

// Every k-th sample (k = decimation), keeping samples k, 2k, ... (1-based).
MeasurementSeries decimate(const MeasurementSeries& series, int decimation);

}  // namespace pc_ekf
