#include "pc_ekf/model/road_input.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "pc_ekf/model/course_motion.h"
#include "pc_ekf/model/road_profile.h"

namespace pc_ekf {

namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;

// Times of the four corners of one trapezoid that starts at travel `start` (docs/method.md §1.5).
void addCorners(const SpeedBumpSettings& s, double start, double t0, double t1,
                std::vector<double>& out) {
  const double v = s.speed_kmh / 3.6;
  const double at[4] = {start, start + s.ramp_up_length, start + s.ramp_up_length + s.flat_length,
                        start + s.ramp_up_length + s.flat_length + s.ramp_down_length};
  for (double d : at) {
    const double t = d / v;
    if (t > t0 && t < t1) out.push_back(t);
  }
}

// An iso8608 course segment in its own time tau (CourseRoad): the profile
// driven at `speed` (both tracks at distance speed * tau, as
// DrivenProfileRoad's two contacts; under a brake or an acceleration
// speed * tau + accel tau^2 / 2), blended from `from` over the lead-in.
class CourseIso8608 : public RoadInput {
 public:
  CourseIso8608(const Iso8608Settings& s, double speed, const Eigen::Vector2d& from,
                double accel = 0.0)
      : profile_(s), speed_(speed), accel_(accel), lead_in_(s.lead_in), from_(from) {}
  Eigen::Vector2d height(double tau) const override {
    double s = speed_ * tau;
    if (accel_ != 0.0) s += 0.5 * accel_ * tau * tau;
    Eigen::Vector2d h = profile_.bothTracks(s);
    if (from_[0] != 0.0 || from_[1] != 0.0) h += (1.0 - iso8608LeadIn(s, lead_in_)) * from_;
    return h;
  }
  // Smooth, as the standalone profile (the lead-in is C1).
  std::vector<double> breakpoints(double, double) const override { return {}; }

 private:
  Iso8608Profile profile_;
  double speed_, accel_, lead_in_;
  Eigen::Vector2d from_;
};

// A manoeuvre on a measured profile in its own time tau (CourseRoad): both
// tracks at distance start + speed tau (+ accel tau^2 / 2), shifted so that
// the segment starts at `from` (the profile's own offset there taken out).
class CourseMeasured : public RoadInput {
 public:
  CourseMeasured(std::shared_ptr<const TrackProfile> profile, double start, double speed,
                 const Eigen::Vector2d& from, double accel)
      : profile_(std::move(profile)), start_(start), speed_(speed), accel_(accel),
        shift_(from - profile_->bothTracks(start)) {}
  Eigen::Vector2d height(double tau) const override {
    return profile_->bothTracks(start_ + distance(tau)) + shift_;
  }
  // The profile's kinks, at the times the wheels reach them.
  std::vector<double> breakpoints(double t0, double t1) const override {
    std::vector<double> out;
    const double a = std::max(t0, 0.0);
    if (!(t1 > a)) return out;
    for (double s : profile_->kinks(start_ + distance(a), start_ + distance(t1))) {
      const double d = s - start_;
      const double tau = accel_ == 0.0 ? d / speed_
                                       : (std::sqrt(std::max(0.0, speed_ * speed_ + 2.0 * accel_ * d)) -
                                          speed_) / accel_;
      if (tau > t0 && tau < t1) out.push_back(tau);
    }
    return out;
  }

 private:
  double distance(double tau) const { return speed_ * tau + 0.5 * accel_ * tau * tau; }
  std::shared_ptr<const TrackProfile> profile_;
  double start_, speed_, accel_;
  Eigen::Vector2d shift_;
};

std::string describeTime(const std::string& what, double t) {
  std::ostringstream os;
  os.precision(17);
  os << "SampledRoad: " << what << " at t = " << t;
  return os.str();
}

}  // namespace

void checkSpeedBump(const SpeedBumpSettings& s, const std::string& who) {
  const double values[] = {s.speed_kmh,   s.height_left,      s.height_right,   s.ramp_up_length,
                           s.flat_length, s.ramp_down_length, s.delay_fraction, s.start_distance};
  for (double v : values) {
    if (!std::isfinite(v)) throw std::invalid_argument(who + ": non-finite setting");
  }
  if (s.speed_kmh <= 0.0) throw std::invalid_argument(who + ": speed_kmh must be > 0");
  if (s.ramp_up_length < 0.0 || s.flat_length < 0.0 || s.ramp_down_length < 0.0 ||
      s.delay_fraction < 0.0) {
    throw std::invalid_argument(who + ": lengths and delay_fraction must be >= 0");
  }
}

SpeedBumpRoad::SpeedBumpRoad(const SpeedBumpSettings& s) : s_(s) {
  checkSpeedBump(s, "SpeedBumpRoad");
}

double unitTrapezoid(double d, double up, double flat, double down) {
  const double top = up + flat;
  const double total = top + down;
  if (d <= 0.0 || d >= total) return 0.0;
  if (d < up) return d / up;
  if (d <= top) return 1.0;
  return (total - d) / down;
}

Eigen::Vector2d SpeedBumpRoad::height(double t) const {
  const double travel = s_.speed_kmh / 3.6 * t - s_.start_distance;
  const double total = s_.ramp_up_length + s_.flat_length + s_.ramp_down_length;
  const auto shape = [&](double d) {
    return unitTrapezoid(d, s_.ramp_up_length, s_.flat_length, s_.ramp_down_length);
  };
  return {s_.height_left * shape(travel),
          s_.height_right * shape(travel - s_.delay_fraction * total)};
}

std::vector<double> SpeedBumpRoad::breakpoints(double t0, double t1) const {
  const double total = s_.ramp_up_length + s_.flat_length + s_.ramp_down_length;
  std::vector<double> out;
  addCorners(s_, s_.start_distance, t0, t1, out);
  addCorners(s_, s_.start_distance + s_.delay_fraction * total, t0, t1, out);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

SineRoad::SineRoad(const SineSettings& s) : s_(s) {
  if (!std::isfinite(s.amplitude) || !std::isfinite(s.frequency) || !std::isfinite(s.right_sign)) {
    throw std::invalid_argument("SineRoad: non-finite setting");
  }
}

Eigen::Vector2d SineRoad::height(double t) const {
  const double y1 = s_.amplitude * std::sin(kTwoPi * s_.frequency * t);
  return {y1, s_.right_sign * y1};
}

double CourseRoad::speedBumpDuration(const SpeedBumpSettings& s) {
  const SpeedBumpRoad bump(s);
  const double total = s.ramp_up_length + s.flat_length + s.ramp_down_length;
  const double end = (s.start_distance + (1.0 + s.delay_fraction) * total) / (s.speed_kmh / 3.6);
  const auto corners = bump.breakpoints(-1.0, 2.0 * end + 1.0);
  // The last corner itself, so the boundary coincides with it bit for bit.
  return corners.empty() ? end : corners.back();
}

CourseRoad::CourseRoad(std::vector<CourseSegment> segments) {
  if (segments.empty()) throw std::invalid_argument("CourseRoad: no segments");
  start_.push_back(0.0);
  level_.push_back(Eigen::Vector2d::Zero());
  for (std::size_t i = 0; i < segments.size(); ++i) {
    const CourseSegment& seg = segments[i];
    double d = seg.duration;
    bool blends = false;
    if (seg.type == CourseSegment::Type::kSpeedBump) {
      roads_.push_back(std::make_unique<SpeedBumpRoad>(seg.speed_bump));
      d = speedBumpDuration(seg.speed_bump);
    } else if (seg.type == CourseSegment::Type::kSine) {
      roads_.push_back(std::make_unique<SineRoad>(seg.sine));
    } else if (seg.isManoeuvre() && seg.manoeuvre.measured) {
      if (!(seg.speed_kmh >= 0.0) || !std::isfinite(seg.speed_kmh) ||
          !std::isfinite(seg.manoeuvre.profile_start) ||
          (seg.speed_kmh == 0.0 && seg.longitudinalAcceleration() <= 0.0)) {
        throw std::invalid_argument("CourseRoad: segment " + std::to_string(i) +
                                    " (surface profile): the vehicle must move along it");
      }
      roads_.push_back(std::make_unique<CourseMeasured>(
          seg.manoeuvre.measured, seg.manoeuvre.profile_start, seg.speed_kmh / 3.6, level_.back(),
          seg.longitudinalAcceleration()));
      blends = true;
    } else if (seg.type == CourseSegment::Type::kIso8608 ||
               (seg.isManoeuvre() && seg.manoeuvre.rough)) {
      const std::string who = "CourseRoad: segment " + std::to_string(i) + " (iso8608)";
      if (!(seg.speed_kmh > 0.0) || !std::isfinite(seg.speed_kmh)) {
        throw std::invalid_argument(who + ": speed_kmh must be finite and > 0");
      }
      if (!(seg.iso8608.lead_in > 0.0) || !std::isfinite(seg.iso8608.lead_in)) {
        throw std::invalid_argument(who + ": lead_in must be finite and > 0 (the segment "
                                    "blends from the heights it starts at over it)");
      }
      try {
        roads_.push_back(
            std::make_unique<CourseIso8608>(seg.iso8608, seg.speed_kmh / 3.6, level_.back(),
                                            seg.longitudinalAcceleration()));
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument(who + ": " + e.what());
      }
      blends = true;
    } else {
      roads_.push_back(nullptr);
    }
    if (!(d > 0.0) || !std::isfinite(d)) {
      throw std::invalid_argument("CourseRoad: segment duration must be finite and > 0");
    }
    blends_.push_back(blends);
    start_.push_back(start_.back() + d);
    // An iso8608 segment leaves the heights it ended at (its own time d);
    // every other segment the level it started from.
    level_.push_back(blends ? roads_.back()->height(d) : level_.back());
  }
  motion_ = std::make_shared<CourseMotion>(segments, start_);
}

Eigen::Vector2d CourseRoad::height(double t) const {
  if (t >= start_.back()) return level_.back();
  const std::size_t i =
      t < start_[1] ? 0 : std::upper_bound(start_.begin(), start_.end(), t) - start_.begin() - 1;
  if (!roads_[i]) return level_[i];
  Eigen::Vector2d h = roads_[i]->height(t - start_[i]);
  // Levels are 0 until an iso8608 segment: nothing added (not even a 0).
  if (!blends_[i] && (level_[i][0] != 0.0 || level_[i][1] != 0.0)) h += level_[i];
  return h;
}

std::vector<double> CourseRoad::breakpoints(double t0, double t1) const {
  std::vector<double> out;
  for (std::size_t i = 0; i < roads_.size(); ++i) {
    const double a = start_[i], b = start_[i + 1];
    if (b <= t0 || a >= t1 || !roads_[i]) continue;
    for (double local : roads_[i]->breakpoints(t0 - a, t1 - a)) {
      const double t = a + local;
      if (t > t0 && t < t1) out.push_back(t);
    }
  }
  for (double b : start_) {
    if (b > t0 && b < t1) out.push_back(b);
  }
  for (double b : motion_->breakpoints(t0, t1)) out.push_back(b);  // a turn's ramps
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

SampledRoad::SampledRoad(int contacts) : heights_(contacts) {
  if (contacts < 1) throw std::invalid_argument("SampledRoad: at least one contact");
}

SampledRoad::SampledRoad(const std::vector<double>& t,
                         const std::vector<std::vector<double>>& heights)
    : heights_(heights.size()) {
  if (heights.empty()) throw std::invalid_argument("SampledRoad: at least one contact");
  for (const auto& h : heights) {
    if (h.size() != t.size()) {
      throw std::invalid_argument("SampledRoad: time and value series differ in length");
    }
  }
  std::vector<double> row(heights.size());
  for (std::size_t k = 0; k < t.size(); ++k) {
    for (std::size_t c = 0; c < heights.size(); ++c) row[c] = heights[c][k];
    append(t[k], row);
  }
}

void SampledRoad::append(double t, const std::vector<double>& heights) {
  if (!std::isfinite(t)) throw std::invalid_argument(describeTime("non-finite time", t));
  if (!t_.empty() && !(t > t_.back())) {
    throw std::invalid_argument(describeTime("time not after the last sample", t));
  }
  if (heights.size() != heights_.size()) {
    throw std::invalid_argument(describeTime(std::to_string(heights.size()) + " heights for " +
                                                 std::to_string(heights_.size()) + " contacts",
                                             t));
  }
  for (double h : heights) {
    if (!std::isfinite(h)) throw std::invalid_argument(describeTime("non-finite height", t));
  }
  t_.push_back(t);
  for (std::size_t c = 0; c < heights.size(); ++c) heights_[c].push_back(heights[c]);
}

std::size_t SampledRoad::indexNeededFor(double t) const {
  // First sample strictly after t; the one before it (if any) is needed for interpolation.
  const auto after = std::upper_bound(t_.begin(), t_.end(), t);
  return after == t_.begin() ? 0 : static_cast<std::size_t>(after - t_.begin()) - 1;
}

void SampledRoad::discardBefore(double t) {
  const auto n = static_cast<std::ptrdiff_t>(indexNeededFor(t));
  t_.erase(t_.begin(), t_.begin() + n);
  for (auto& h : heights_) h.erase(h.begin(), h.begin() + n);
}

double SampledRoad::firstTime() const {
  if (t_.empty()) throw std::logic_error("SampledRoad::firstTime on an empty road");
  return t_.front();
}

double SampledRoad::lastTime() const {
  if (t_.empty()) throw std::logic_error("SampledRoad::lastTime on an empty road");
  return t_.back();
}

void SampledRoad::heights(double t, Eigen::Ref<Eigen::VectorXd> out) const {
  const std::size_t n = heights_.size();
  if (t_.empty()) {
    out.setZero();  // no input yet: road at rest
    return;
  }
  if (t <= t_.front() || t >= t_.back()) {
    const std::size_t k = t <= t_.front() ? 0 : t_.size() - 1;
    for (std::size_t c = 0; c < n; ++c) out[c] = heights_[c][k];
    return;
  }
  const std::size_t i = std::upper_bound(t_.begin(), t_.end(), t) - t_.begin() - 1;
  const double w = (t - t_[i]) / (t_[i + 1] - t_[i]);
  for (std::size_t c = 0; c < n; ++c) {
    out[c] = heights_[c][i] + w * (heights_[c][i + 1] - heights_[c][i]);
  }
}

std::vector<double> SampledRoad::breakpoints(double t0, double t1) const {
  const auto first = std::upper_bound(t_.begin(), t_.end(), t0);
  const auto last = std::lower_bound(t_.begin(), t_.end(), t1);
  if (first >= last) return {};
  return std::vector<double>(first, last);
}

}  // namespace pc_ekf
