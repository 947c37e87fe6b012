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

// A road's cross-fall (crown) under the vehicle: beta, rad, left side up > 0
// (a 2 % cross-fall is beta = 0.02). `start` from t = 0, changing to `end`
// by a half-cosine over [at, at + over] s (over 0: a step at `at`, from
// t > at; start == end: constant). Time-based: at speed V the change spans V over metres.
struct CrossFall {
  double start = 0.0, end = 0.0, at = 0.0, over = 0.0;
  bool active() const { return start != 0.0 || end != 0.0; }
  double angle(double t) const;
  double rate(double t) const;  // d beta / dt, rad/s
};

// A motion on a cross-fall: the vehicle, tilted rigidly with the road by
// beta, feels gravity's component g sin(beta) along its y axis as a lateral
// specific force: a_y of `inner` (null: none) plus g sin(beta(t)); speed and
// yaw rate are inner's. (g cos(beta) for the vertical is not applied: a
// 2e-4 relative difference at 2 %.) The gyro's share, d beta / dt, is added
// to the readings by the synthetic drive (SyntheticDataSettings::roll_rate).
class CrossFallMotion : public HorizontalMotion {
 public:
  CrossFallMotion(std::shared_ptr<const ContactRoad> road, const CrossFall& cross_fall,
                  double gravity);
  HorizontalState at(double t) const override;
  std::vector<double> breakpoints(double t0, double t1) const override;
  bool accelerates() const override { return true; }

 private:
  std::shared_ptr<const ContactRoad> road_;  // keeps the inner motion alive
  const HorizontalMotion* inner_;
  CrossFall c_;
  double gravity_;
};

// The union of two sorted breakpoint lists, sorted, without duplicates.
std::vector<double> mergeBreakpoints(std::vector<double> a, const std::vector<double>& b);

}  // namespace pc_ekf
