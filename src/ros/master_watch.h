// Keeps a node in the graph across a restart of the ROS master. roscpp
// registers topics and services with the master once, when they are created;
// a restarted master knows nothing of them (rosnode list empty, no new
// connections) and roscpp never registers again. MasterWatch asks the master
// once per period, on a thread of its own (a master that does not answer
// must not hold up the callbacks), and when a master answers that does not
// know this node, registers every publication, subscription and the given
// services of this process again through the Master API. Nothing the node
// holds is re-created: filter state, queues and the connections that
// survived the master stay as they are.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace pc_ekf {

struct MasterStatus {
  bool reachable = true;
  int pid = 0;                 // of the master last reached
  std::uint64_t restarts = 0;  // new masters registered with
  std::string last_change;     // wall time (s since the epoch) of the last re-registration
  std::string last_report;     // what the last re-registration registered, or why it failed
};

class MasterWatch {
 public:
  // `services`: resolved names of this node's services to register again.
  MasterWatch(std::vector<std::string> services, double period);
  ~MasterWatch();  // stops the thread (within one master call)
  MasterWatch(const MasterWatch&) = delete;
  MasterWatch& operator=(const MasterWatch&) = delete;

  MasterStatus status() const;

 private:
  void loop();
  void check();
  // Registers everything with the master now answering; returns the summary.
  std::string reregister();

  const std::vector<std::string> services_;
  const double period_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  MasterStatus status_;
  std::thread thread_;  // last: starts once the members above exist
};

}  // namespace pc_ekf
