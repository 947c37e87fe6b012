// Lossless replay at any speed: after publishing a sample, replay_node waits
// for the estimator's parameter_estimate stamped like that sample before it
// publishes the next one, so no sample is lost. Callbacks come from another
// thread (ros::AsyncSpinner); waits use the wall clock, so /use_sim_time
// does not stall them.
#pragma once

#include <pc_ekf/ParameterEstimate.h>
#include <ros/node_handle.h>
#include <ros/subscriber.h>

#include <condition_variable>
#include <cstddef>
#include <mutex>
#include <optional>
#include <string>

namespace pc_ekf {

class EstimateHandshake {
 public:
  EstimateHandshake(ros::NodeHandle& nh, const std::string& estimate_topic);

  // True once the estimator's publisher is connected to us.
  bool connected() const { return subscriber_.getNumPublishers() > 0; }
  std::string topic() const { return subscriber_.getTopic(); }

  // Call BEFORE publishing the sample stamped `stamp`, so that an answer
  // arriving at once is not missed.
  void expect(const ros::Time& stamp);
  // Waits until the expected sample was answered (true; also when nothing is
  // pending), `timeout_s` passed or ROS shut down (false; counted).
  bool waitForAnswer(double timeout_s);

  std::size_t answered() const;
  std::size_t unanswered() const;
  std::size_t received() const;
  // The last estimate received (for the summary), if any.
  std::optional<ParameterEstimate> lastEstimate() const;

 private:
  void onEstimate(const ParameterEstimate::ConstPtr& msg);

  ros::Subscriber subscriber_;
  mutable std::mutex mutex_;
  std::condition_variable answer_;
  std::optional<ros::Time> pending_;
  std::size_t answered_ = 0, unanswered_ = 0, received_ = 0;
  ParameterEstimate::ConstPtr last_;
};

// "added_mass = 223.2 +- 0.068, added_mass_position = 0.688 +- 0.0003".
std::string describeEstimate(const ParameterEstimate& msg);

}  // namespace pc_ekf
