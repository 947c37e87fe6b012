// Known road excitation under the two tyres (docs/method.md §1.5).
#pragma once

#include <Eigen/Dense>
#include <memory>
#include <string>
#include <vector>

namespace pc_ekf {

// The road under any number of contacts (a model's contact names, in order).
class ContactRoad {
 public:
  virtual ~ContactRoad() = default;
  virtual int contactCount() const = 0;
  // Heights (m, up positive, 0 at rest) under every contact at t; out has
  // contactCount() entries.
  virtual void heights(double t, Eigen::Ref<Eigen::VectorXd> out) const = 0;
  // Times in the open interval (t0, t1) where the input has a kink; the
  // integrator stops there so its order holds across them.
  virtual std::vector<double> breakpoints(double t0, double t1) const = 0;
};

// A road under two contacts (the roll plane's tyres).
class RoadInput : public ContactRoad {
 public:
  // Road heights (m, up positive, 0 at rest) under tyre 1 (left) and tyre 2 (right).
  virtual Eigen::Vector2d height(double t) const = 0;
  int contactCount() const override { return 2; }
  void heights(double t, Eigen::Ref<Eigen::VectorXd> out) const override { out = height(t); }
};

struct SpeedBumpSettings {
  double speed_kmh = 16.0;
  double height_left = 0.10;
  double height_right = 0.08;
  double ramp_up_length = 1.0;   // m of travel
  double flat_length = 1.0;      // m
  double ramp_down_length = 1.0; // m
  double delay_fraction = 0.2;   // of the bump length, for tyre 2
  double start_distance = 0.0;   // m of travel before tyre 1 reaches the bump
};

// Throws std::invalid_argument, prefixed by `who`, for a non-finite setting,
// speed_kmh <= 0 or a negative length or delay_fraction.
void checkSpeedBump(const SpeedBumpSettings& s, const std::string& who);

// Unit-height trapezoid at travel d past its start: ramp up over `up`, flat
// over `flat`, ramp down over `down`; 0 outside; zero-length ramps are steps.
double unitTrapezoid(double d, double up, double flat, double down);

// Trapezoid bump seen by both tyres, tyre 2 delayed (docs/method.md §1.5).
class SpeedBumpRoad : public RoadInput {
 public:
  explicit SpeedBumpRoad(const SpeedBumpSettings& s);
  Eigen::Vector2d height(double t) const override;
  std::vector<double> breakpoints(double t0, double t1) const override;
 private:
  SpeedBumpSettings s_;
};

struct SineSettings {
  double amplitude = 0.05;  // m
  double frequency = 1.0;   // Hz
  double right_sign = -1.0; // y2 = right_sign * y1 (out of phase by default)
};

class SineRoad : public RoadInput {
 public:
  explicit SineRoad(const SineSettings& s);
  Eigen::Vector2d height(double t) const override;
  std::vector<double> breakpoints(double, double) const override { return {}; }
 private:
  SineSettings s_;
};

// One piece of a course road; durations in s.
struct CourseSegment {
  enum class Type { kSpeedBump, kSine, kRest };
  Type type = Type::kRest;
  SpeedBumpSettings speed_bump;
  SineSettings sine;
  double duration = 0.0;  // sine and rest; a speed bump lasts until both tyres are past it
};

// Segments played one after another, each in its own time from 0 (a sine
// starts at phase 0); flat road after the last one. Segment boundaries are
// breakpoints, so a step where a sine ends is integrated exactly.
class CourseRoad : public RoadInput {
 public:
  // Throws std::invalid_argument for no segments, a bad bump or a duration <= 0.
  explicit CourseRoad(std::vector<CourseSegment> segments);
  Eigen::Vector2d height(double t) const override;
  std::vector<double> breakpoints(double t0, double t1) const override;
  // Start time of each segment and the course's end.
  const std::vector<double>& boundaries() const { return start_; }
  // Time for both tyres to be past the bump (its last corner).
  static double speedBumpDuration(const SpeedBumpSettings& s);
 private:
  std::vector<std::unique_ptr<RoadInput>> roads_;  // null for rest
  std::vector<double> start_;  // one per segment, then the course's end
};

// A sampled series under any number of contacts, linearly
// interpolated and held constant outside its span. Samples can be appended
// (road from a topic); times must increase strictly.
class SampledRoad : public ContactRoad {
 public:
  explicit SampledRoad(int contacts);
  // heights[c][k]: contact c at t[k]. Throws std::invalid_argument.
  SampledRoad(const std::vector<double>& t, const std::vector<std::vector<double>>& heights);
  // Throws std::invalid_argument when t is not strictly after the last sample,
  // values are not finite or their count is not contactCount().
  void append(double t, const std::vector<double>& heights);
  // Index of the first sample that interpolation at times >= t needs: the one
  // at or before t (0 when t precedes every sample).
  std::size_t indexNeededFor(double t) const;
  // Drops samples older than t, keeping the one at or before t (bounded buffers).
  void discardBefore(double t);
  bool empty() const { return t_.empty(); }
  std::size_t size() const { return t_.size(); }
  double firstTime() const;
  double lastTime() const;
  const std::vector<double>& times() const { return t_; }
  const std::vector<double>& column(int contact) const { return heights_[contact]; }
  int contactCount() const override { return static_cast<int>(heights_.size()); }
  void heights(double t, Eigen::Ref<Eigen::VectorXd> out) const override;
  std::vector<double> breakpoints(double t0, double t1) const override;
 private:
  std::vector<double> t_;
  std::vector<std::vector<double>> heights_;  // [contact][sample]
};

}  // namespace pc_ekf
