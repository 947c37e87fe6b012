// A speed bump crossed by the four wheels of the full car (front_left,
// front_right, rear_left, rear_right): the trapezoid of SpeedBumpRoad, the
// right wheels delay_fraction of the bump's length behind the left ones (an
// oblique bump), the rear wheels one wheelbase behind the front ones.
#pragma once

#include <vector>

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

}  // namespace pc_ekf
