#include "pc_ekf/ros/replay_handshake.h"

#include <ros/console.h>

#include <chrono>
#include <iomanip>
#include <sstream>

namespace pc_ekf {

EstimateHandshake::EstimateHandshake(ros::NodeHandle& nh, const std::string& estimate_topic) {
  // Estimates are small and answer one sample each: a modest queue suffices.
  subscriber_ = nh.subscribe(estimate_topic, 100, &EstimateHandshake::onEstimate, this);
}

void EstimateHandshake::expect(const ros::Time& stamp) {
  std::lock_guard<std::mutex> lock(mutex_);
  pending_ = stamp;
}

bool EstimateHandshake::waitForAnswer(double timeout_s) {
  std::unique_lock<std::mutex> lock(mutex_);
  if (!pending_) return true;
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                            std::chrono::duration<double>(timeout_s));
  // Short slices so that a shutdown (Ctrl-C) is noticed promptly.
  while (pending_ && ros::ok() && std::chrono::steady_clock::now() < deadline) {
    answer_.wait_for(lock, std::chrono::milliseconds(50));
  }
  if (!pending_) return true;
  ROS_WARN("replay_node: no %s stamped %u.%09u within %.3g s; going on", topic().c_str(),
           pending_->sec, pending_->nsec, timeout_s);
  pending_.reset();
  ++unanswered_;
  return false;
}

void EstimateHandshake::onEstimate(const ParameterEstimate::ConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++received_;
  last_ = msg;
  if (pending_ && msg->header.stamp == *pending_) {
    pending_.reset();
    ++answered_;
    answer_.notify_all();
  }
}

std::size_t EstimateHandshake::answered() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return answered_;
}

std::size_t EstimateHandshake::unanswered() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return unanswered_;
}

std::size_t EstimateHandshake::received() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return received_;
}

std::optional<ParameterEstimate> EstimateHandshake::lastEstimate() const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!last_) return std::nullopt;
  return *last_;
}

std::string describeEstimate(const ParameterEstimate& msg) {
  std::ostringstream o;
  o << std::setprecision(6);
  for (std::size_t i = 0; i < msg.names.size(); ++i) {
    o << (i ? ", " : "") << msg.names[i];
    if (i < msg.mean.size()) o << " = " << msg.mean[i];
    if (i < msg.stddev.size()) o << " +- " << msg.stddev[i];
  }
  return o.str();
}

}  // namespace pc_ekf
