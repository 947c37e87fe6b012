// Known road excitation under the two tyres (docs/method.md §1.5).
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace pc_ekf {

class HorizontalMotion;
class TrackProfile;

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
  // The vehicle's horizontal motion on this drive (turns, braking), when the
  // drive has one; null: straight at constant speed (horizontal_motion.h).
  virtual const HorizontalMotion* horizontalMotion() const { return nullptr; }
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

// ISO 8608 roughness: displacement PSD Gd(n) = Gd(n0) (n / n0)^-2, n0 = 0.1
// cycles/m, Gd(n0) the class's geometric mean (A 16, B 64, C 256, D 1024,
// E 4096, in 1e-6 m^3). A sum of `bands` sinusoids over [n_min, n_max]
// cycles/m (log-spaced bands of width dn, amplitude sqrt(2 Gd(n) dn), seeded
// random phases): smooth, so no kinks. The right track is
// correlation * left + sqrt(1 - correlation^2) * an independent track (0:
// independent, the harder case for roll; 1: the same). Faded in over the
// first lead_in metres (a smooth step), so a vehicle at rest at s = 0 starts
// on level ground. The profile itself: Iso8608Profile (road_profile.h).
struct Iso8608Settings {
  char road_class = 'B';  // A..E
  std::uint64_t seed = 1;
  double correlation = 0.0;
  double n_min = 0.02, n_max = 5.0;  // cycles/m: wavelengths 50 m .. 0.2 m
  int bands = 200;
  double lead_in = 2.0;  // m
};

// A lateral manoeuvre (course segments turn, lane_change, slalom), driven at
// the segment's speed_kmh; a_y left positive (a left turn, REP 103):
//  - turn: a_y = lateral_acceleration (or V^2 / radius when radius != 0),
//    reached and left over `ramp` s by half-cosines;
//  - lane_change: one period of a_y = lateral_acceleration sin(2 pi t / duration)
//    (out to one side and straight again: a lane's offset, ISO 3888-1-like);
//  - slalom: a_y = lateral_acceleration sin(2 pi frequency t).
// The road under it: flat (the level where the segment before left it),
// rough, the ISO 8608 road of the segment's iso8608 settings (as an iso8608
// segment), or a measured profile driven from `profile_start` m into it,
// shifted to start at that level.
// Longitudinal manoeuvres (course segments brake, accelerate): the speed
// falls (brake) or rises (accelerate) from speed_kmh at a constant rate,
// `longitudinal` m/s^2 (> 0; the end speed must stay >= 0), on the same
// surfaces; a_x = dV/dt.
struct ManoeuvreSettings {
  double lateral_acceleration = 3.0;  // m/s^2: the turn's, the peak of the others
  double longitudinal = 3.0;          // brake: deceleration, accelerate: acceleration, m/s^2
  double radius = 0.0;                // turn, m, left positive; 0: lateral_acceleration
  double ramp = 1.0;                  // turn, s
  double frequency = 0.5;             // slalom, Hz
  bool rough = false;                 // surface iso8608 (else flat)
  std::shared_ptr<const TrackProfile> measured;  // surface profile (null: not)
  double profile_start = 0.0;         // m into the measured profile
};

// One piece of a course road; durations in s.
struct CourseSegment {
  enum class Type {
    kSpeedBump, kSine, kRest, kIso8608, kTurn, kLaneChange, kSlalom, kBrake, kAccelerate
  };
  Type type = Type::kRest;
  SpeedBumpSettings speed_bump;
  SineSettings sine;
  Iso8608Settings iso8608;  // iso8608 segment (and a rough manoeuvre): its profile
  ManoeuvreSettings manoeuvre;  // turn, lane_change, slalom
  double speed_kmh = 36.0;  // iso8608 segment and manoeuvres: driving speed
  double duration = 0.0;  // all but a speed bump, which lasts until both tyres are past it
  bool isManoeuvre() const {
    return type == Type::kTurn || type == Type::kLaneChange || type == Type::kSlalom ||
           isLongitudinal();
  }
  bool isLongitudinal() const { return type == Type::kBrake || type == Type::kAccelerate; }
  // dV/dt over a longitudinal manoeuvre (0 for any other segment).
  double longitudinalAcceleration() const {
    return type == Type::kBrake ? -manoeuvre.longitudinal
                                : type == Type::kAccelerate ? manoeuvre.longitudinal : 0.0;
  }
};

// Segments played one after another, each in its own time from 0 (a sine
// starts at phase 0, an ISO 8608 segment at distance 0 of its profile).
// Segment boundaries are breakpoints, so a step where a sine ends is
// integrated exactly.
//
// Levels: each segment starts from a level (heights of both tracks; 0 for the
// first) and leaves one for the next:
//  - rest holds its level: the vehicle stands still, the road under it does
//    not move;
//  - speed_bump and sine are their shapes on top of their level and leave it
//    as they found it (a bump ends at 0; a sine ending off zero steps back to
//    its level, a breakpoint);
//  - iso8608 is driven at its speed_kmh: its profile P (Iso8608Profile at
//    distance s = V tau) blended from its level L with the profile's own
//    lead-in weight w(s) (0 at s = 0, 1 from lead_in on, C1):
//    h = P(s) + (1 - w(s)) L, which starts at L and is the standalone
//    profile itself from lead_in on; it leaves the heights it ended at.
//    A stop after it therefore holds the heights where the vehicle stopped
//    (speed changes are instantaneous: a kink at the boundary).
// After the last segment the road stays at the level the last one left.
// Levels are 0 until an iso8608 segment has been driven: a course of speed
// bumps, sines and rests is flat road at exactly 0 between and after them,
// its bumps and sines the standalone roads' heights bit for bit.
class CourseRoad : public RoadInput {
 public:
  // Throws std::invalid_argument for no segments, a bad bump, a duration <= 0,
  // or an iso8608 segment with a speed <= 0, a bad profile or no lead-in (a
  // lead_in of 0 would step from its level onto the profile).
  explicit CourseRoad(std::vector<CourseSegment> segments);
  Eigen::Vector2d height(double t) const override;
  std::vector<double> breakpoints(double t0, double t1) const override;
  // Start time of each segment and the course's end.
  const std::vector<double>& boundaries() const { return start_; }
  // The level each segment starts from, then the one after the course.
  const std::vector<Eigen::Vector2d>& levels() const { return level_; }
  // Time for both tyres to be past the bump (its last corner).
  static double speedBumpDuration(const SpeedBumpSettings& s);
  // The drive's horizontal motion when a segment is a manoeuvre (null
  // otherwise: the course is driven straight, a_y = 0).
  const HorizontalMotion* horizontalMotion() const override { return motion_.get(); }
 private:
  std::vector<std::unique_ptr<RoadInput>> roads_;  // null for rest
  std::vector<bool> blends_;   // iso8608: the road blends from its level itself
  std::vector<double> start_;  // one per segment, then the course's end
  std::vector<Eigen::Vector2d> level_;  // one per segment, then the one after the course
  std::shared_ptr<const HorizontalMotion> motion_;
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
