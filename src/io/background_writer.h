// Runs file writes on one background thread so that the caller (a sample
// callback) only hands over a job. Latest wins: a job submitted while an
// earlier one is still waiting replaces it (only the newest state is worth
// writing); a job already running finishes. The thread runs at the lowest
// priority (SCHED_IDLE, else nice 19). Errors are kept for the caller to
// report on its own thread.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace pc_ekf {

class BackgroundWriter {
 public:
  using Job = std::function<void()>;

  BackgroundWriter();
  // flush(), then stops the thread.
  ~BackgroundWriter();
  BackgroundWriter(const BackgroundWriter&) = delete;
  BackgroundWriter& operator=(const BackgroundWriter&) = delete;

  void submit(Job job);
  // Returns once every submitted job has run.
  void flush();
  // Drops the waiting job and returns once the running one (if any) is done:
  // afterwards no job touches the file until the next submit.
  void cancel();

  // what() of the jobs that threw since the last call.
  std::vector<std::string> takeErrors();
  std::uint64_t written() const;     // jobs run to completion without throwing
  std::uint64_t superseded() const;  // jobs replaced or cancelled before they ran

 private:
  void loop();

  mutable std::mutex mutex_;
  std::condition_variable wake_, idle_;
  Job pending_;
  bool running_ = false;
  bool stop_ = false;
  std::vector<std::string> errors_;
  std::uint64_t written_ = 0, superseded_ = 0;
  std::thread thread_;  // last: starts once the members above exist
};

}  // namespace pc_ekf
