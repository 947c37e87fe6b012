// The horizontal motion of a course (road_input.h's CourseRoad): each
// segment's speed, the lateral acceleration of its manoeuvre, and the
// longitudinal one of a brake or an acceleration (the speed changing at that
// rate from the segment's speed_kmh).
#pragma once

#include <vector>

#include "pc_ekf/model/horizontal_motion.h"
#include "pc_ekf/model/road_input.h"

namespace pc_ekf {

class CourseMotion : public HorizontalMotion {
 public:
  // start: each segment's start time, then the course's end. Speeds: a
  // manoeuvre's, a speed bump's and an iso8608 segment's speed_kmh; 0 at
  // rest and on a sine (a shaker). Throws std::invalid_argument for a
  // manoeuvre with a speed <= 0, a frequency <= 0 or a negative ramp.
  CourseMotion(const std::vector<CourseSegment>& segments, std::vector<double> start);
  HorizontalState at(double t) const override;
  // The turns' ramp ends (segment boundaries are the road's breakpoints).
  std::vector<double> breakpoints(double t0, double t1) const override;
  bool accelerates() const override { return manoeuvres_; }
  // a_y of one manoeuvre at local time tau in [0, duration] (0 otherwise).
  static double lateral(const CourseSegment& s, double speed, double tau);
  // Distance driven from t = 0 to t (the speed's integral; a rest and a sine
  // do not move), and the first time the distance reaches s (0 for s <= 0;
  // the course's end when it never does).
  double distance(double t) const;
  double timeAtDistance(double s) const;

 private:
  std::vector<CourseSegment> segments_;
  std::vector<double> start_, speed_;
  std::vector<double> travelled_;  // distance at each segment's start, then at the end
  bool manoeuvres_ = false;
};

}  // namespace pc_ekf
