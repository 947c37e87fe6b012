#include "pc_ekf/model/full_car_road.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace pc_ekf {

FullCarBumpRoad::FullCarBumpRoad(const FullCarBumpSettings& s)
    : s_(s),
      right_offset_(s.bump.delay_fraction *
                    (s.bump.ramp_up_length + s.bump.flat_length + s.bump.ramp_down_length)) {
  checkSpeedBump(s.bump, "FullCarBumpRoad");
  if (s.bump.start_distance != 0.0) {
    throw std::invalid_argument("full_car speed bump: road.speed_bump.start_distance must be 0");
  }
  if (!(std::isfinite(s.wheelbase) && s.wheelbase >= 0.0)) {
    throw std::invalid_argument("FullCarBumpRoad: wheelbase must be finite, >= 0");
  }
}

double FullCarBumpRoad::offset(int c) const {
  return (c % 2 == 1 ? right_offset_ : 0.0) + (c >= 2 ? s_.wheelbase : 0.0);
}

void FullCarBumpRoad::heights(double t, Eigen::Ref<Eigen::VectorXd> out) const {
  const SpeedBumpSettings& b = s_.bump;
  const double travel = b.speed_kmh / 3.6 * t;
  for (int c = 0; c < 4; ++c) {
    const double h = c % 2 == 0 ? b.height_left : b.height_right;
    out[c] = h * unitTrapezoid(travel - offset(c), b.ramp_up_length, b.flat_length,
                               b.ramp_down_length);
  }
}

std::vector<double> FullCarBumpRoad::breakpoints(double t0, double t1) const {
  const SpeedBumpSettings& b = s_.bump;
  const double v = b.speed_kmh / 3.6;
  std::vector<double> out;
  for (int c = 0; c < 4; ++c) {
    const double start = offset(c);
    const double at[4] = {start, start + b.ramp_up_length, start + b.ramp_up_length + b.flat_length,
                          start + b.ramp_up_length + b.flat_length + b.ramp_down_length};
    for (double d : at) {
      const double t = d / v;
      if (t > t0 && t < t1) out.push_back(t);
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

FullCarCourseRoad::FullCarCourseRoad(const std::vector<CourseSegment>& segments, double wheelbase)
    : course_(segments), motion_(segments, course_.boundaries()), wheelbase_(wheelbase) {
  if (!(std::isfinite(wheelbase) && wheelbase >= 0.0)) {
    throw std::invalid_argument("FullCarCourseRoad: wheelbase must be finite, >= 0");
  }
  const double end = course_.boundaries().back();
  std::vector<double> front = course_.breakpoints(-1.0, end + 1.0);
  front.push_back(0.0);  // the rear wheels reach the course's start
  for (double b : front) {
    const double s = motion_.distance(b) + wheelbase_;
    if (s >= motion_.distance(end)) continue;  // the rear wheels never get there
    rear_breakpoints_.push_back(motion_.timeAtDistance(s));
  }
  std::sort(rear_breakpoints_.begin(), rear_breakpoints_.end());
}

double FullCarCourseRoad::rearTime(double t) const {
  const double s = motion_.distance(t) - wheelbase_;
  if (s < 0.0) return -1.0;
  return motion_.timeAtDistance(s);
}

void FullCarCourseRoad::heights(double t, Eigen::Ref<Eigen::VectorXd> out) const {
  const Eigen::Vector2d front = course_.height(t);
  const double rear_t = rearTime(t);
  const Eigen::Vector2d rear = rear_t < 0.0 ? Eigen::Vector2d::Zero() : course_.height(rear_t);
  out[0] = front[0];
  out[1] = front[1];
  out[2] = rear[0];
  out[3] = rear[1];
}

std::vector<double> FullCarCourseRoad::breakpoints(double t0, double t1) const {
  std::vector<double> out = course_.breakpoints(t0, t1);
  for (double b : rear_breakpoints_) {
    if (b > t0 && b < t1) out.push_back(b);
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace pc_ekf
