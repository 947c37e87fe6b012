// The road of a deferred re-run (docs/realtime.md) when it comes from
// road/profile: the node appends to its road while the re-run's worker reads
// the road, so the worker reads immutable copies instead, a newer one handed
// over (on the node's thread) before each sample it is fed. Within the time
// the samples cover, every copy gives the live road's heights and kinks.
#pragma once

#include <memory>
#include <mutex>
#include <vector>

#include "pc_ekf/model/road_input.h"

namespace pc_ekf {

class RoadSnapshots : public ContactRoad {
 public:
  explicit RoadSnapshots(std::shared_ptr<const SampledRoad> live);
  // Copies the live road (call on the thread that appends to it).
  void update();
  int contactCount() const override { return contacts_; }
  void heights(double t, Eigen::Ref<Eigen::VectorXd> out) const override;
  std::vector<double> breakpoints(double t0, double t1) const override;

 private:
  std::shared_ptr<const SampledRoad> current() const;

  std::shared_ptr<const SampledRoad> live_;
  int contacts_;
  mutable std::mutex mutex_;
  std::shared_ptr<const SampledRoad> copy_;  // guarded by mutex_
};

}  // namespace pc_ekf
