// The vehicle's own horizontal motion, an exogenous input of the models
// (docs/models.md, "Heights, anti-roll bar and lateral acceleration"): forward
// speed and yaw rate, from which the road-frame accelerations follow
// (a_y = V psi_dot, left positive; a_x = dV/dt). Yaw and side slip are not
// modelled. A road without one is a straight drive at a_x = a_y = 0.
#pragma once

#include <Eigen/Dense>
#include <memory>
#include <vector>

#include "pc_ekf/model/road_input.h"

namespace pc_ekf {

struct HorizontalState {
  double speed = 0.0;         // m/s, forward over ground
  double yaw_rate = 0.0;      // rad/s, positive turning left (REP 103)
  double lateral = 0.0;       // a_y, m/s^2, left positive
  double longitudinal = 0.0;  // a_x, m/s^2, positive speeding up
};

class HorizontalMotion {
 public:
  virtual ~HorizontalMotion() = default;
  virtual HorizontalState at(double t) const = 0;
  // Times in the open interval (t0, t1) where the motion has a kink or a
  // step (the integrator stops there).
  virtual std::vector<double> breakpoints(double t0, double t1) const = 0;
  // False when a_x = a_y = 0 throughout (a straight drive: the models keep
  // their paths without horizontal acceleration).
  virtual bool accelerates() const { return true; }
};

// A constant motion from t = 0 on (a steady turn): tests and checks.
class SteadyMotion : public HorizontalMotion {
 public:
  explicit SteadyMotion(const HorizontalState& s) : s_(s) {}
  HorizontalState at(double) const override { return s_; }
  std::vector<double> breakpoints(double, double) const override { return {}; }

 private:
  HorizontalState s_;
};

// A road driven with a horizontal motion: the road's heights, its and the
// motion's breakpoints.
class RoadWithMotion : public ContactRoad {
 public:
  RoadWithMotion(std::shared_ptr<const ContactRoad> road,
                 std::shared_ptr<const HorizontalMotion> motion);
  int contactCount() const override { return road_->contactCount(); }
  void heights(double t, Eigen::Ref<Eigen::VectorXd> out) const override { road_->heights(t, out); }
  std::vector<double> breakpoints(double t0, double t1) const override;
  const HorizontalMotion* horizontalMotion() const override { return motion_.get(); }

 private:
  std::shared_ptr<const ContactRoad> road_;
  std::shared_ptr<const HorizontalMotion> motion_;
};

// The union of two sorted breakpoint lists, sorted, without duplicates.
std::vector<double> mergeBreakpoints(std::vector<double> a, const std::vector<double>& b);

}  // namespace pc_ekf
