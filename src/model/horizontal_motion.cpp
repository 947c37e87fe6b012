// A road driven with a horizontal motion (horizontal_motion.h).
#include "pc_ekf/model/horizontal_motion.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace pc_ekf {

RoadWithMotion::RoadWithMotion(std::shared_ptr<const ContactRoad> road,
                               std::shared_ptr<const HorizontalMotion> motion)
    : road_(std::move(road)), motion_(std::move(motion)) {
  if (!road_ || !motion_) throw std::invalid_argument("RoadWithMotion: needs a road and a motion");
}

std::vector<double> RoadWithMotion::breakpoints(double t0, double t1) const {
  return mergeBreakpoints(road_->breakpoints(t0, t1), motion_->breakpoints(t0, t1));
}

double CrossFall::angle(double t) const {
  if (!(t > at)) return start;
  if (!(t < at + over)) return end;
  return start + (end - start) * 0.5 * (1.0 - std::cos(M_PI * (t - at) / over));
}

double CrossFall::rate(double t) const {
  if (!(t > at) || !(t < at + over)) return 0.0;
  return (end - start) * 0.5 * M_PI / over * std::sin(M_PI * (t - at) / over);
}

CrossFallMotion::CrossFallMotion(std::shared_ptr<const ContactRoad> road,
                                 const CrossFall& cross_fall, double gravity)
    : road_(std::move(road)),
      inner_(road_ ? road_->horizontalMotion() : nullptr),
      c_(cross_fall),
      gravity_(gravity) {}

HorizontalState CrossFallMotion::at(double t) const {
  HorizontalState s = inner_ ? inner_->at(t) : HorizontalState();
  s.lateral += gravity_ * std::sin(c_.angle(t));
  return s;
}

std::vector<double> CrossFallMotion::breakpoints(double t0, double t1) const {
  std::vector<double> b = inner_ ? inner_->breakpoints(t0, t1) : std::vector<double>();
  std::vector<double> own;
  for (double t : {c_.at, c_.at + c_.over}) {
    if (t > t0 && t < t1) own.push_back(t);
  }
  return mergeBreakpoints(b, own);
}

std::vector<double> mergeBreakpoints(std::vector<double> a, const std::vector<double>& b) {
  a.insert(a.end(), b.begin(), b.end());
  std::sort(a.begin(), a.end());
  a.erase(std::unique(a.begin(), a.end()), a.end());
  return a;
}

}  // namespace pc_ekf
