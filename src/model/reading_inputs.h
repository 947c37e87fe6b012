// Readings used as inputs (road-free estimation, docs/method.md §4.10): a
// record's channels by time, linearly interpolated, held before the first
// and after the last sample; the sample times themselves, and running
// integrals. A whole record fills a missing value from its neighbours; a
// stream holds the last one. A stream that runs for hours forgets the
// samples no estimator will read again (forget()): the integrals run on, a
// tail and optionally the record's first samples (a batch's) stay.
#pragma once

#include <Eigen/Dense>
#include <cstddef>
#include <functional>
#include <shared_mutex>
#include <string>
#include <vector>

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
  // previousTime(), integral() and sampleSum() may run on other threads
  // meanwhile (a deferred re-linearisation's worker, the node's batch
  // service); the other members belong to the appending thread.
  std::string append(double t, const double* values);
  bool empty() const { return samples_ == 0; }
  int count() const { return static_cast<int>(names_.size()); }
  const std::vector<std::string>& names() const { return names_; }
  // Samples appended so far, and the time of sample k (counted from the
  // first, forgotten ones too); std::out_of_range for a forgotten sample.
  std::size_t samples() const { return samples_; }
  std::size_t held() const;  // of them, in memory (not forgotten)
  double time(std::size_t k) const;
  // Every input at t. The readers below throw std::logic_error when they
  // would need a forgotten sample.
  void at(double t, double* out) const;
  // The latest sample time before t (0 when none: the vehicle at rest).
  double previousTime(double t) const;
  // The integral of input c from 0 to t (trapezoids; 0 before the first
  // sample's value is assumed from t = 0 on).
  double integral(int c, double t) const;

  // A sum over every sample of f(its inputs), kept up to date as samples
  // are appended, so that forgotten samples still count (a tare record's
  // weighed load). Registering is a cache's kind of change (the inputs stay
  // what they are), hence const; it must come before anything is
  // forgotten (std::logic_error). Returns the sum's handle for sampleSum().
  int addSampleSum(std::function<double(const double*)> f) const;
  double sampleSum(int handle) const;

  // Forgets the samples that no reader will need again: those before the
  // sample at or before `needed_from` (the one before it stays, for
  // previousTime()), except those at or before `kept_until` (the record's
  // first samples, a batch's: -infinity keeps none). The last two samples
  // always stay. Work and memory stay bounded: samples go in chunks, once
  // there are as many to forget as stay after them.
  void forget(double needed_from, double kept_until);

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
  // Stored samples: the record's first `prefix_` (when some were
  // forgotten), then after `skipped_` forgotten ones the rest.
  bool frontForgotten() const { return skipped_ > 0 && prefix_ == 0; }
  // True when t lies between the last kept first sample and the first
  // sample after the forgotten ones (i: the stored sample before t).
  bool inGap(std::size_t i, double t) const {
    return skipped_ > 0 && i + 1 == prefix_ && t > t_[i];
  }
  [[noreturn]] void forgotten(const char* what, double t) const;

  std::vector<std::string> names_;
  std::vector<double> t_;
  std::vector<std::vector<double>> v_;    // [input][stored sample], gaps filled
  std::vector<std::vector<double>> cum_;  // [input][stored sample]: integral up to t
  std::size_t samples_ = 0, prefix_ = 0, skipped_ = 0;
  mutable std::vector<std::function<double(const double*)>> sum_terms_;
  mutable std::vector<double> sums_;
  std::vector<double> rho_;  // [input]: lag-1 noise correlation
  bool integral_in_state_ = false;
  // append() and forget() against the readers. A lock, not the copies a
  // topic road hands its re-runs (RoadSnapshots): a copy per sample would
  // cost the kept samples each.
  mutable std::shared_mutex mutex_;
};

}  // namespace pc_ekf
