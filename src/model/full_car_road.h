// A speed bump crossed by the four wheels of the full car (front_left,
// front_right, rear_left, rear_right): the same trapezoid as SpeedBumpRoad,
// the right wheels `right_offset` of travel behind the left ones, the rear
// wheels one wheelbase behind the front ones.
#pragma once

#include <vector>

#include "pc_ekf/model/road_input.h"

namespace pc_ekf {

struct FullCarBumpSettings {
  double speed_kmh = 16.0;
  double height_left = 0.10;
  double height_right = 0.08;
  double ramp_up_length = 1.0;    // m of travel
  double flat_length = 1.0;       // m
  double ramp_down_length = 1.0;  // m
  double right_offset = 0.6;      // m of travel before the right wheels reach the bump
  double wheelbase = 2.6;         // m: the nominal vehicle's FullCarParameters::wheelbase()
};

class FullCarBumpRoad : public ContactRoad {
 public:
  // Throws std::invalid_argument for non-finite settings, speed <= 0 or a
  // negative length, offset or wheelbase.
  explicit FullCarBumpRoad(const FullCarBumpSettings& s);
  int contactCount() const override { return 4; }
  void heights(double t, Eigen::Ref<Eigen::VectorXd> out) const override;
  std::vector<double> breakpoints(double t0, double t1) const override;
  const FullCarBumpSettings& settings() const { return s_; }

 private:
  // Travel at which contact c reaches the bump.
  double offset(int c) const;
  FullCarBumpSettings s_;
};

}  // namespace pc_ekf
