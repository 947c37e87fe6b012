// A speed bump crossed by the four wheels of the full car (front_left,
// front_right, rear_left, rear_right): the trapezoid of SpeedBumpRoad, the
// right wheels delay_fraction of the bump's length behind the left ones (an
// oblique bump), the rear wheels one wheelbase behind the front ones.
#pragma once

#include <memory>
#include <vector>

#include "pc_ekf/model/course_motion.h"
#include "pc_ekf/model/road_input.h"

namespace pc_ekf {

// road.speed_bump's settings (start_distance must be 0) and the wheelbase.
struct FullCarBumpSettings {
  SpeedBumpSettings bump;
  double wheelbase = 2.6;  // m: the nominal vehicle's FullCarParameters::wheelbase()
};

class FullCarBumpRoad : public ContactRoad {
 public:
  // Throws std::invalid_argument for what SpeedBumpRoad rejects, a
  // start_distance other than 0 or a negative or non-finite wheelbase.
  explicit FullCarBumpRoad(const FullCarBumpSettings& s);
  int contactCount() const override { return 4; }
  void heights(double t, Eigen::Ref<Eigen::VectorXd> out) const override;
  std::vector<double> breakpoints(double t0, double t1) const override;
  const FullCarBumpSettings& settings() const { return s_; }

 private:
  // Travel at which contact c reaches the bump.
  double offset(int c) const;
  FullCarBumpSettings s_;
  double right_offset_;  // m of travel before the right wheels reach the bump
};

// A course (road.source course) under the full car's four wheels: the front
// wheels on the course's left and right tracks, the rear ones a wheelbase
// behind them by distance driven (the course's motion: a rest and a sine
// segment do not move the vehicle, so the rear wheels stay where they are;
// before the rear wheels reach the course's start the road under them is 0).
// It carries the course's horizontal motion (turns, braking).
class FullCarCourseRoad : public ContactRoad {
 public:
  // Throws what CourseRoad throws, or std::invalid_argument for a negative
  // or non-finite wheelbase.
  FullCarCourseRoad(const std::vector<CourseSegment>& segments, double wheelbase);
  int contactCount() const override { return 4; }
  void heights(double t, Eigen::Ref<Eigen::VectorXd> out) const override;
  std::vector<double> breakpoints(double t0, double t1) const override;
  const HorizontalMotion* horizontalMotion() const override { return &motion_; }
  // The time at which the front wheels were where the rear ones are at t
  // (negative: the rear wheels are not on the course yet).
  double rearTime(double t) const;

 private:
  CourseRoad course_;
  CourseMotion motion_;
  double wheelbase_;
  std::vector<double> rear_breakpoints_;  // the course's breakpoints as the rear wheels meet them
};

}  // namespace pc_ekf
