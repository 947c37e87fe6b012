// A course's horizontal motion (course_motion.h).
#include "pc_ekf/model/course_motion.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace pc_ekf {
namespace {

constexpr double kPi = 3.14159265358979323846;

double speedOf(const CourseSegment& s) {
  using T = CourseSegment::Type;
  if (s.type == T::kSpeedBump) return s.speed_bump.speed_kmh / 3.6;
  if (s.type == T::kIso8608 || s.isManoeuvre()) return s.speed_kmh / 3.6;
  return 0.0;
}

// A turn's ramps: half as long as the turn at most.
double turnRamp(const CourseSegment& s) { return std::min(s.manoeuvre.ramp, 0.5 * s.duration); }

}  // namespace

CourseMotion::CourseMotion(const std::vector<CourseSegment>& segments, std::vector<double> start)
    : segments_(segments), start_(std::move(start)) {
  if (start_.size() != segments_.size() + 1) {
    throw std::invalid_argument("CourseMotion: one start per segment and the end");
  }
  for (std::size_t i = 0; i < segments_.size(); ++i) {
    const CourseSegment& s = segments_[i];
    speed_.push_back(speedOf(s));
    if (!s.isManoeuvre()) continue;
    if (s.isLongitudinal()) {
      const std::string who = "CourseRoad: segment " + std::to_string(i) + " (" +
                              (s.type == CourseSegment::Type::kBrake ? "brake" : "accelerate") +
                              ")";
      if (!(speed_.back() >= 0.0) || !std::isfinite(speed_.back())) {
        throw std::invalid_argument(who + ": speed_kmh must be finite and >= 0");
      }
      const double rate = s.manoeuvre.longitudinal;
      if (!(rate > 0.0) || !std::isfinite(rate)) {
        throw std::invalid_argument(who + ": the acceleration must be finite and > 0 m/s^2");
      }
      if (speed_.back() + s.longitudinalAcceleration() * s.duration < -1e-9) {
        throw std::invalid_argument(who + ": stops before its end (speed_kmh / 3.6 < " +
                                    "deceleration x duration)");
      }
      manoeuvres_ = true;
      continue;
    }
    manoeuvres_ = true;
    const std::string who = "CourseRoad: segment " + std::to_string(i) + " (manoeuvre)";
    const ManoeuvreSettings& m = s.manoeuvre;
    if (!(speed_.back() > 0.0) || !std::isfinite(speed_.back())) {
      throw std::invalid_argument(who + ": speed_kmh must be finite and > 0");
    }
    if (!std::isfinite(m.lateral_acceleration) || !std::isfinite(m.radius)) {
      throw std::invalid_argument(who + ": lateral_acceleration and radius must be finite");
    }
    if (s.type == CourseSegment::Type::kTurn && !(m.ramp >= 0.0 && std::isfinite(m.ramp))) {
      throw std::invalid_argument(who + ": ramp must be finite and >= 0");
    }
    if (s.type == CourseSegment::Type::kSlalom &&
        !(m.frequency > 0.0 && std::isfinite(m.frequency))) {
      throw std::invalid_argument(who + ": frequency must be finite and > 0");
    }
  }
  travelled_.push_back(0.0);
  for (std::size_t i = 0; i < segments_.size(); ++i) {
    const double d = start_[i + 1] - start_[i];
    travelled_.push_back(travelled_.back() + speed_[i] * d +
                         0.5 * segments_[i].longitudinalAcceleration() * d * d);
  }
}

double CourseMotion::lateral(const CourseSegment& s, double speed, double tau) {
  if (!s.isManoeuvre() || tau < 0.0 || tau > s.duration) return 0.0;
  const ManoeuvreSettings& m = s.manoeuvre;
  switch (s.type) {
    case CourseSegment::Type::kTurn: {
      const double a = m.radius != 0.0 ? speed * speed / m.radius : m.lateral_acceleration;
      const double ramp = turnRamp(s), edge = std::min(tau, s.duration - tau);
      if (edge >= ramp) return a;
      return a * 0.5 * (1.0 - std::cos(kPi * edge / ramp));
    }
    case CourseSegment::Type::kLaneChange:
      return m.lateral_acceleration * std::sin(2.0 * kPi * tau / s.duration);
    case CourseSegment::Type::kSlalom:
      return m.lateral_acceleration * std::sin(2.0 * kPi * m.frequency * tau);
    default:
      return 0.0;
  }
}

HorizontalState CourseMotion::at(double t) const {
  HorizontalState h;
  if (t < 0.0 || t >= start_.back()) return h;  // before and after the course: standing
  const std::size_t i = std::upper_bound(start_.begin(), start_.end(), t) - start_.begin() - 1;
  h.speed = speed_[i];
  if (segments_[i].isLongitudinal()) {
    h.longitudinal = segments_[i].longitudinalAcceleration();
    h.speed = std::max(0.0, speed_[i] + h.longitudinal * (t - start_[i]));
    return h;  // straight: a_y = 0
  }
  h.lateral = lateral(segments_[i], h.speed, t - start_[i]);
  h.yaw_rate = h.speed > 0.0 ? h.lateral / h.speed : 0.0;  // a_y = V psi'
  return h;
}

double CourseMotion::distance(double t) const {
  if (t <= 0.0) return 0.0;
  if (t >= start_.back()) return travelled_.back();
  const std::size_t i = std::upper_bound(start_.begin(), start_.end(), t) - start_.begin() - 1;
  const double tau = t - start_[i];
  return travelled_[i] + speed_[i] * tau +
         0.5 * segments_[i].longitudinalAcceleration() * tau * tau;
}

double CourseMotion::timeAtDistance(double s) const {
  if (s <= 0.0) return 0.0;
  if (s >= travelled_.back()) return start_.back();
  // The first segment whose end lies beyond s (moving there), then solve
  // V tau + a tau^2 / 2 = s - its start.
  const std::size_t i =
      std::upper_bound(travelled_.begin(), travelled_.end(), s) - travelled_.begin() - 1;
  const double rest = s - travelled_[i], v = speed_[i],
               a = segments_[i].longitudinalAcceleration();
  double tau = 0.0;
  if (a == 0.0) {
    tau = v > 0.0 ? rest / v : 0.0;
  } else {
    const double disc = std::max(0.0, v * v + 2.0 * a * rest);
    tau = 2.0 * rest / (v + std::sqrt(disc));  // the smaller root, stable for a < 0
  }
  return std::min(start_[i] + tau, start_[i + 1]);
}

std::vector<double> CourseMotion::breakpoints(double t0, double t1) const {
  std::vector<double> out;
  for (std::size_t i = 0; i < segments_.size(); ++i) {
    if (segments_[i].type != CourseSegment::Type::kTurn) continue;
    const double ramp = turnRamp(segments_[i]);
    for (double t : {start_[i] + ramp, start_[i + 1] - ramp}) {
      if (t > t0 && t < t1) out.push_back(t);
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace pc_ekf
