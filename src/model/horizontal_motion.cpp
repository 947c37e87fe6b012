// A road driven with a horizontal motion (horizontal_motion.h).
#include "pc_ekf/model/horizontal_motion.h"

#include <algorithm>
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

std::vector<double> mergeBreakpoints(std::vector<double> a, const std::vector<double>& b) {
  a.insert(a.end(), b.begin(), b.end());
  std::sort(a.begin(), a.end());
  a.erase(std::unique(a.begin(), a.end()), a.end());
  return a;
}

}  // namespace pc_ekf
