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
  // Calls job(part, begin, end) for the parts [bounds[i], bounds[i+1]) on
  // parts.size() - 1 <= threads() threads, the caller's thread taking part 0;
  // returns when all are done. Exceptions of a part are rethrown here. Calls
  // from several threads are serialised.
  void run(const std::vector<long>& bounds, const std::function<void(int, long, long)>& job);

  static int defaultThreads();

 private:
  void workerLoop(int index);

  int threads_ = 1;
  std::mutex run_mutex_;  // one run() at a time
  std::mutex mutex_;      // sleeping and waking, error_
  std::condition_variable start_, done_;
  // Published by run() before generation_ is incremented (release/acquire).
  std::vector<long> begins_, ends_;  // part of worker i (empty: none this run)
  const std::function<void(int, long, long)>* job_ = nullptr;
  std::atomic<long> generation_{0};
  std::atomic<int> pending_{0};
  std::atomic<bool> stop_{false};
  std::exception_ptr error_;
  std::vector<std::thread> workers_;
};

// Part boundaries over `count` columns for up to `threads` parts of at least
// `min_columns` each, every inner boundary a multiple of `align` (the SIMD
// width: each column then meets the same vector/remainder code path as in
// one batch). One part (0, count) when splitting does not pay.
std::vector<long> columnParts(long count, int threads, long min_columns, long align = 8);

}  // namespace pc_ekf
