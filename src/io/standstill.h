// A vehicle standing still (measurement.standstill, docs/method.md §4.10):
// its suspension travels and rates then carry only their sensors' noise.
// Taken as they are, that noise reads as motion the IMU does not see (errors
// in variables with no signal): the damper rates and springs are pulled a
// little at every sample, which over a long stop adds up to several std.
// While standing, a travel is the mean of its readings since the stop began
// and a rate is zero; the covariance a prediction inherits shrinks to match.
#pragma once
#include <deque>
#include <vector>

namespace pc_ekf {

class Standstill {
 public:
  // window (s; 0: never standing): the stretch over which a stop is
  // recognised. travels, rates: input indices; absolute, relative: each
  // input's raw noise std (absolute, and relative to the reading).
  Standstill(double window, std::vector<int> travels, std::vector<int> rates,
             std::vector<double> absolute, std::vector<double> relative);

  struct Decision {
    bool standing = false;
    long averaged = 0;  // readings in each travel's mean (standing)
  };
  // For the raw inputs `in` at t: standing is entered when over the last
  // `window` s (this sample included) every rate's RMS is below 1.5 times
  // its noise std and every travel's spread about its mean below 1.5 times
  // its own (noise alone stays far below both) with its window's halves'
  // means within 3 std of each other (no step), and left at the first rate
  // or travel beyond 5 std of zero or of the stop's mean, or when a travel's
  // mean over the last window is 5 of its std off the stop's (a small load
  // put in). Changes nothing.
  Decision decide(double t, const std::vector<double>& in) const;
  // Writes the standing inputs into `in`: travels their means, rates 0.
  void apply(const Decision& d, const std::vector<double>& raw, std::vector<double>* in) const;
  // Takes the sample (raw inputs) with its decision.
  void commit(double t, const std::vector<double>& raw, const Decision& d);
  bool enabled() const { return window_ > 0.0; }
  bool standing() const { return standing_; }  // at the last sample taken
  long standingSamples() const { return standing_samples_; }
  long stops() const { return stops_; }

 private:
  double sigma(int input, double reading) const;
  double window_;
  std::vector<int> travels_, rates_;
  std::vector<double> absolute_, relative_;
  // The last `window` s: times, and the raw inputs row after row (a deque
  // grows and shrinks in blocks: nothing allocated per sample).
  std::deque<double> times_, values_;
  double value(std::size_t row, std::size_t input) const { return values_[row * sums_.size() + input]; }
  bool standing_ = false;
  long count_ = 0;            // readings in the stop's means
  std::vector<double> sums_;  // per input: the stop's travel sums
  long standing_samples_ = 0, stops_ = 0;
};

}  // namespace pc_ekf
