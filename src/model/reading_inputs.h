// Readings used as inputs (road-free estimation, docs/method.md §4.10): a
// record's channels by time, linearly interpolated, held before the first
// and after the last sample; the sample times themselves, and running
// integrals. A whole record fills a missing value from its neighbours; a
// stream holds the last one.
#pragma once

#include <Eigen/Dense>
#include <shared_mutex>
#include <string>
#include <vector>

#include "pc_ekf/model/road_input.h"

namespace pc_ekf {

class ReadingInputs {
 public:
  // columns[c][k]: input c at times[k] (NaN = not read at that sample).
  // Throws std::invalid_argument for no samples, times not increasing or an
  // input never read.
  ReadingInputs(std::vector<std::string> names, std::vector<double> times,
                std::vector<std::vector<double>> columns);
  // A stream (the node, and estimate_offline the same way): no samples yet,
  // each one appended as it arrives.
  explicit ReadingInputs(std::vector<std::string> names);
  // values[c]: input c at t (NaN = not read: held at its last value). Returns
  // "" or why the sample cannot be taken (t not after the last sample, an
  // input not read yet or infinite); then nothing changes. at(),
  // previousTime() and integral() may run on other threads meanwhile (a
  // deferred re-linearisation's worker reads the samples before the one
  // being appended); the other readers belong to the appending thread.
  std::string append(double t, const double* values);
  bool empty() const { return t_.empty(); }
  int count() const { return static_cast<int>(names_.size()); }
  const std::vector<std::string>& names() const { return names_; }
  const std::vector<double>& times() const { return t_; }
  // Every input at t.
  void at(double t, double* out) const;
  // The latest sample time before t (0 when none: the vehicle at rest).
  double previousTime(double t) const;
  // The integral of input c from 0 to t (trapezoids; 0 before the first
  // sample's value is assumed from t = 0 on).
  double integral(int c, double t) const;
  // Mean and RMS of input c over the samples.
  double mean(int c) const;
  double rms(int c) const;
  // The correlation of input c's noise between consecutive samples (0: white;
  // a blended travel's is about its blend factor). Errors in variables use it
  // for an output read from the inputs at a sample and at the one before.
  void setNoiseCorrelation(int c, double rho);
  double noiseCorrelation(int c) const;
  // True when the estimator carries the random walk of input c's integral
  // as a state of its own (filter.linearization: mean): errors in variables
  // then leave that walk out of the inherited noise.
  void setIntegralInState(bool in_state) { integral_in_state_ = in_state; }
  bool integralInState() const { return integral_in_state_; }

 private:
  std::vector<std::string> names_;
  std::vector<double> t_;
  std::vector<std::vector<double>> v_;    // [input][sample], gaps filled
  std::vector<std::vector<double>> cum_;  // [input][sample]: integral up to t_k
  SampledRoad series_;                    // v_ by time, for the interpolation
  std::vector<double> rho_;               // [input]: lag-1 noise correlation
  bool integral_in_state_ = false;
  // append() against at(), previousTime(), integral(). A lock, not the copies
  // a topic road hands its re-runs (RoadSnapshots): these inputs keep the
  // whole record, so a copy per sample would cost O(samples) each.
  mutable std::shared_mutex mutex_;
};

}  // namespace pc_ekf
