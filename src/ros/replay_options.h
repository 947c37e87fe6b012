// Parameters of replay_node (private namespace), loaded once and validated.
// docs/nodes.md "replay_node" documents each one.
#pragma once

#include <ros/node_handle.h>

#include <stdexcept>
#include <string>
#include <vector>

namespace pc_ekf {

// An invalid parameter; the message names the parameter and the value.
class ReplayOptionError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ReplayOptions {
  std::string bag;  // required
  // Playback speed relative to the recorded timing; 0 = as fast as possible.
  double rate = 1.0;
  // Before the first message: wait until every topic of `subscriber_topics`
  // has `min_subscribers` connected and every subscriber the master knows for
  // a replayed topic is connected (so nothing is published into the void).
  bool wait_for_subscribers = true;
  std::vector<std::string> subscriber_topics = {"suspension/joint_states"};
  int min_subscribers = 1;
  double wait_timeout = 0.0;  // s; 0 = wait forever
  double start_delay = 0.0;   // s, after the wait
  // Per-connection outgoing queue; 0 = the topic's message count, so a whole
  // pass fits and the publisher never drops at any rate.
  int queue_size = 0;
  bool loop = false;
  // Handshake: publish the next message on `lossless_topic` only once an
  // estimate stamped like the previous one arrived on `estimate_topic`.
  bool lossless = false;
  std::string lossless_topic = "suspension/joint_states";  // bag topic suffix
  std::string estimate_topic = "parameter_estimate";       // relative
  double lossless_timeout = 10.0;                          // s per sample
  bool publish_clock = false;                              // bag time on /clock (for /use_sim_time)
  double linger = 1.0;  // s alive after the last message (delivery)
};

// Reads ~bag, ~rate, ... from `private_nh`. Throws ReplayOptionError.
ReplayOptions loadReplayOptions(const ros::NodeHandle& private_nh);

}  // namespace pc_ekf
