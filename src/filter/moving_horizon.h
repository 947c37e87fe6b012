// The one-step filter linearised at its mean, over a moving horizon
// (filter.linearization: mean, docs/method.md §4.11). The parameters' law is
// carried as a Gaussian in standardised coordinates (zeta = (theta - prior
// mean) / prior std); each sample is predicted at the mean and at one step
// along each parameter, so the update uses the model's exact Jacobian there
// instead of a projection over the spread, and a parameter the readings do
// not depend on never moves. The samples of the current window are kept;
// at its end, when a mean has moved further than `shift` posterior std from
// where a sample was linearised, the window is re-run from its own prior
// with every sample linearised at the window's final mean (a Gauss-Newton
// iteration, at most `reruns` times); then its posterior becomes the next
// window's prior. Memory and cost per sample do not grow with the record.
//
// Road-free roll plane: the roll angle is the gyro's integral, and its
// integrated noise is one random walk shared by every later sample, not
// noise of its own per sample. It is carried as one more state, the angle's
// error e (rad, variance growing by (sigma_gyro dt)^2 a sample), that
// accel_y and accel_z see through their slope in the angle; the readings'
// inherited noise then leaves it out (ReadingInputs::integralInState).
//
// settings.input_noise_states: the inputs' noise as states too, each
// input's (standardised) at this sample and at the one before, advanced by
// the sample's lag-1 correlation (Measurement::input_slopes); the sample's
// R keeps only what is not carried.
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <deque>
#include <functional>
#include <memory>
#include <limits>
#include <string>
#include <vector>

#include "pc_ekf/filter/kalman_update.h"
#include "pc_ekf/filter/measurement.h"
#include "pc_ekf/filter/pc_propagator.h"
#include "pc_ekf/filter/update_safeguards.h"

namespace pc_ekf {

// What one sample's update did (the caller applies gate and damping).
struct HorizonStep {
  UpdateDiagnostics update;
  bool gated = false;
  double damping = 1.0;
  int reruns = 0;  // window re-runs at this sample (its window's end)
};

class MovingHorizon {
 public:
  // Throws std::invalid_argument when the model has dynamic states (it needs
  // a model whose readings are algebraic in its inputs: road.source none).
  MovingHorizon(const PcPropagator& propagator, const MovingHorizonSettings& settings);

  void reset();  // the prior
  // gate_bound(dof) <= 0: no gate. lower/upper: parameter supports (damping
  // when damp is true).
  template <class Gate>
  HorizonStep process(const Measurement& m, const NoiseModel& noise, const Gate& gate_bound,
                      bool damp) {
    Recent before{m, 0.0, 0, mean_, cov_, previous_time_};
    Eigen::VectorXd mean_after;
    Eigen::MatrixXd cov_after;
    HorizonStep s = propose(m, noise, &mean_after, &cov_after);
    if (s.update.finite) {
      const double bound = gate_bound(s.update.channels);
      if (bound > 0.0 && s.update.nis > bound) s.gated = true;
      before.nis = s.update.nis;
      before.dof = s.update.channels;
    }
    accept(m, s, mean_after, cov_after, damp);
    remember(std::move(before));
    return s;
  }
  // The last `count` samples' states are kept (0: none), so that a change
  // can be rewound to (rewindToChange).
  void keepRecent(int count);
  // Among the last `within` samples kept, how many samples back the change
  // most likely began: the start of the suffix whose NIS exceeds level(dof)
  // by the most (a CUSUM change point; a level above the NIS's mean keeps
  // the unchanged samples before it out). 0: none kept.
  int samplesSinceChange(int within, const std::function<double(int)>& level) const;
  // Back to the state before the sample `back` samples ago (1: the last);
  // returns the samples from there on, to be processed again; ends the window.
  std::vector<Measurement> rewind(int back);
  // The parameters' expansion (count x S): affine, mean and covariance exact.
  Eigen::MatrixXd coefficients() const;
  // Sets the Gaussian from an affine expansion (a checkpoint); ends the window.
  void restore(const Eigen::MatrixXd& coefficients);
  // Rows `rows` back to their prior, uncorrelated with the others (a load
  // change: the vehicle values keep what was learned). Ends the window.
  void reopen(const std::vector<int>& rows);
  // Random walk: variance intensity_i^2 dt added to parameter i.
  void drift(const Eigen::VectorXd& intensity, double dt);
  long evaluations() const { return evaluations_ + own_.evaluations + helper_.evaluations; }
  double lastTime() const { return previous_time_; }  // the last sample's time
  // The first sample time a re-run may read (infinity: none kept): the
  // window's, a load change's rewind over the recent samples, and the clock
  // offset's slope four samples before each.
  double windowStart() const;
  // True for channels whose roll angle integrates the gyro: accel_y,
  // accel_z and gyro_x, and no pitch (the roll plane).
  static bool carriesRollAngle(const std::vector<std::string>& channels);
  // The roll angle's error: mean and std (rad); 0 when not carried.
  double rollAngleError() const { return angle_ ? mean_[last()] : 0.0; }
  double rollAngleErrorStd() const { return angle_ ? std::sqrt(cov_(last(), last())) : 0.0; }
  // The clock offset (s): how much later the predicted channels (the IMU)
  // are stamped than the inputs (the suspension) for one instant; NaN when
  // not estimated (settings.clock_offset 0).
  double clockOffset() const;
  double clockOffsetStd() const;
  // Nuisance values (settings.cross_fall, accel_bias, gyro_bias > 0; NaN:
  // not estimated): the road's cross-fall under the vehicle now (rad, left
  // side up > 0), the accel_y and accel_z biases (m/s^2) and the gyro_x
  // bias (rad/s); mean and std.
  double crossFall() const { return stateOr(cross_, 1.0, false); }
  double crossFallStd() const { return stateOr(cross_, 1.0, true); }
  double accelYBias() const { return stateOr(bias_y_, 1.0, false); }
  double accelYBiasStd() const { return stateOr(bias_y_, 1.0, true); }
  double accelZBias() const { return stateOr(bias_z_, 1.0, false); }
  double accelZBiasStd() const { return stateOr(bias_z_, 1.0, true); }
  double gyroBias() const { return stateOr(bias_g_, 1.0, false); }
  double gyroBiasStd() const { return stateOr(bias_g_, 1.0, true); }
  bool nuisance() const { return settings_.nuisance(); }
  // With a clock offset, a sample is processed once the inputs after it,
  // up to 3 prior std of the offset and a difference step beyond, are in:
  // process() those at least this much older than the latest input. 0:
  // process every sample when it comes.
  double readingLag(double dt) const;

 private:
  struct Recent {  // a sample and the state before it
    Measurement m;
    double nis = 0.0;  // 0 with dof 0: not finite
    int dof = 0;
    Eigen::VectorXd mean;
    Eigen::MatrixXd cov;
    double previous_time = 0.0;
  };
  void remember(Recent r);
  std::deque<Recent> recent_;
  std::size_t recent_capacity_ = 0;
  struct Kept {
    Measurement m;
    double dt = 0.0;
    Eigen::VectorXd linearised_at;
    bool used = true;
  };
  HorizonStep propose(const Measurement& m, const NoiseModel& noise, Eigen::VectorXd* mean,
                      Eigen::MatrixXd* cov);
  void accept(const Measurement& m, HorizonStep& s, const Eigen::VectorXd& mean,
              const Eigen::MatrixXd& cov, bool damp);
  // Predicted readings of m's channels at zeta and along each parameter
  // (whitened); false when a point is not admissible or not finite.
  // dt: the time since the sample before (the clock offset's slope).
  // The last prepared batches (many columns, and one: the offset's slope),
  // kept with their full parameters: a window's re-run predicts every sample
  // at one point, and its static equilibria are solved once. One workspace
  // per thread that predicts (the filter's, a re-run's helper).
  struct Prepared {
    Eigen::MatrixXd full;
    std::unique_ptr<ModelBatch> batch;
    bool offsets = false;
    Prepared() = default;
    Prepared(const Prepared&) {}  // a copy of the filter prepares afresh
    Prepared& operator=(const Prepared&) {
      batch.reset();
      return *this;
    }
  };
  struct Workspace {
    Prepared prepared[2];
    long evaluations = 0;  // model evaluations made here
  };
  bool predict(const Measurement& m, double dt, const NoiseModel& noise,
               const Eigen::VectorXd& at, Eigen::VectorXd* values, Eigen::VectorXd* z0,
               Eigen::MatrixXd* jacobian, Eigen::VectorXd* variances, Workspace& ws) const;
  // Readings (model state rows) of parameter columns th at `time`, the
  // inputs `shift` earlier (ModelBatch::readingsShifted).
  // roll, lateral: per column, the roll offset and lateral specific force
  // the model takes (ModelBatch::offsetPoints); empty: none.
  bool readingsAt(const Eigen::MatrixXd& th, double time, Eigen::ArrayXXd& y, Workspace& ws,
                  double shift = 0.0, const Eigen::VectorXd& roll = Eigen::VectorXd(),
                  const Eigen::VectorXd& lateral = Eigen::VectorXd()) const;
  void endWindow(HorizonStep& s);
  Workspace own_;     // the filter's thread
  Workspace helper_;  // the second thread of a window's re-run
  // reopen() with the roll angle carried: the angle's error moved to the
  // new load's static tilt (false: not possible, nothing changed).
  bool reanchorAngle(const std::vector<int>& rows);
  // The roll angles atan2(accel_y, accel_z) of readings y (one per column).
  Eigen::ArrayXd tilts(const Eigen::ArrayXXd& y) const;
  // Readings of parameter columns th (theta) with the angle at the anchor's
  // tilt (after a load change); false: not admissible or not finite.
  bool anchoredReadings(const Eigen::MatrixXd& th, double time, Eigen::ArrayXXd& y,
                        double shift, const Eigen::VectorXd& roll, const Eigen::VectorXd& lateral,
                        Workspace& ws) const;
  std::vector<int> anchor_rows_;  // the load's rows, once a load change came
  Eigen::VectorXd anchor_;        // theta: the load at the start (its mean then)
  void startWindow();
  Eigen::VectorXd theta(const Eigen::VectorXd& zeta) const {
    return prior_mean_ + prior_std_.cwiseProduct(zeta);
  }

  const PcPropagator& propagator_;
  const NoiseModel* noise_ = nullptr;
  int parameters_ = 0;
  bool angle_ = false;  // the roll angle's error is the last state
  int accel_y_ = -1, accel_z_ = -1, gyro_ = -1;
  double previous_time_ = 0.0;
  double last_gap_ = 0.0;  // the last sample's time since the one before
  int last() const { return parameters_; }  // the angle's row
  int offset_ = -1;  // the clock offset's row (units of settings_.clock_offset); -1: none
  // Nuisance rows (physical units; -1: none): the road's cross-fall beta
  // (rad), accel_y's and accel_z's bias (m/s^2), gyro_x's (rad/s). With
  // settings_.nuisance() the angle's error (and the gyro bias's drift) enter
  // the model's roll, the cross-fall its lateral specific force g sin(beta).
  int cross_ = -1, bias_y_ = -1, bias_z_ = -1, bias_g_ = -1;
  double stateOr(int row, double scale, bool stddev) const {
    if (row < 0) return std::numeric_limits<double>::quiet_NaN();
    return stddev ? scale * std::sqrt(std::max(0.0, cov_(row, row))) : scale * mean_[row];
  }
  // The offset (s) a state value stands for, held within 3 prior std (the
  // inputs after the shifted instant are in: readingLag).
  double shiftedOffset(double state) const;
  // The offset slope's difference step: the sample interval dt, at most the
  // offset's prior std.
  double differenceStep(double dt) const;
  void walk(Eigen::MatrixXd& cov, double dt) const;  // the last sample's (window re-runs)
  // The inputs' noise states from the sample before to m's: the one before
  // takes this one's, this one rho times itself plus fresh noise.
  void advanceInputs(const Measurement& m, Eigen::VectorXd& mean, Eigen::MatrixXd& cov) const;
  // m's slopes in the input states, when it carries them (else false).
  bool carriesInputs(const Measurement& m) const {
    return input_count_ > 0 && m.input_slopes.cols() == 2 * input_count_ &&
           m.input_correlation.size() == input_count_;
  }
  int inputs_first_ = -1;  // the first input noise state's row (now), then input_count_ before
  int input_count_ = 0;
  MovingHorizonSettings settings_;
  Eigen::VectorXd prior_mean_, prior_std_, lower_, upper_;
  Eigen::VectorXd mean_;  // zeta
  Eigen::VectorXd at_;    // where the last sample was linearised
  Eigen::MatrixXd cov_;
  Eigen::VectorXd window_mean_;  // the window's prior
  Eigen::MatrixXd window_cov_;
  double window_start_ = 0.0;
  std::vector<Kept> kept_;
  std::vector<int> degree_one_;  // basis term of each parameter's germ, degree 1
  Eigen::VectorXd scale_;  // the mass scale's unit direction in zeta (empty: not held)
  long evaluations_ = 0;
};

}  // namespace pc_ekf
