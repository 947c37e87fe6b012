// A small persistent pool that runs one job split into contiguous column
// ranges on several threads: the per-sample forecast is tens of microseconds,
// too short to start threads for every call.
#pragma once

#include <atomic>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace pc_ekf {

class ColumnWorkers {
 public:
  // threads <= 0: the machine's cores (std::thread::hardware_concurrency()).
  explicit ColumnWorkers(int threads);
  ~ColumnWorkers();
  ColumnWorkers(const ColumnWorkers&) = delete;
  ColumnWorkers& operator=(const ColumnWorkers&) = delete;

  int threads() const { return threads_; }
  // Calls job(part, begin, end) once for every part [bounds[i], bounds[i+1]),
  // the parts taken in turn by the caller's thread and the workers (which
  // thread runs a part must not matter to the job); returns when all are
  // done. An exception of a part is rethrown here. Calls from several
  // threads are serialised.
  void run(const std::vector<long>& bounds, const std::function<void(int, long, long)>& job);

  static int defaultThreads();

 private:
  void workerLoop();
  bool runClaimedParts(long generation);

  int threads_ = 1;
  std::mutex run_mutex_;  // one run() at a time
  std::mutex mutex_;      // sleeping and waking, error_
  std::condition_variable start_, done_;
  // Set by run() before generation_ is published (release/acquire).
  std::vector<long> bounds_;
  const std::function<void(int, long, long)>* job_ = nullptr;
  long parts_ = 0;
  std::atomic<long> next_{0};  // generation << 20 | next unclaimed part
  std::atomic<long> done_parts_{0};
  std::atomic<long> generation_{0};
  std::atomic<bool> stop_{false};
  std::exception_ptr error_;
  std::vector<std::thread> workers_;
};

// Part boundaries over `count` columns for up to `parts` parts of at least
// `min_columns` each, every inner boundary a multiple of `align` (the SIMD
// width: each column then meets the same vector/remainder code path as in
// one batch). One part (0, count) when splitting does not pay.
std::vector<long> columnParts(long count, int parts, long min_columns, long align = 8);

}  // namespace pc_ekf
