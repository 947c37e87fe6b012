#include "pc_ekf/ros/estimator_run_road.h"

namespace pc_ekf {

RoadSnapshots::RoadSnapshots(std::shared_ptr<const SampledRoad> live)
    : live_(std::move(live)), contacts_(live_->contactCount()) {
  update();
}

void RoadSnapshots::update() {
  auto copy = std::make_shared<const SampledRoad>(*live_);
  std::lock_guard<std::mutex> lock(mutex_);
  copy_ = std::move(copy);
}

std::shared_ptr<const SampledRoad> RoadSnapshots::current() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return copy_;
}

void RoadSnapshots::heights(double t, Eigen::Ref<Eigen::VectorXd> out) const {
  current()->heights(t, out);
}

std::vector<double> RoadSnapshots::breakpoints(double t0, double t1) const {
  return current()->breakpoints(t0, t1);
}

}  // namespace pc_ekf
