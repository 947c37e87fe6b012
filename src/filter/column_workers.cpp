#include "pc_ekf/filter/column_workers.h"

#include <algorithm>

namespace pc_ekf {

int ColumnWorkers::defaultThreads() {
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

ColumnWorkers::ColumnWorkers(int threads) : threads_(threads <= 0 ? defaultThreads() : threads) {
  for (int i = 1; i < threads_; ++i) workers_.emplace_back([this, i] { workerLoop(i); });
}

ColumnWorkers::~ColumnWorkers() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  start_.notify_all();
  for (auto& w : workers_) w.join();
}

void ColumnWorkers::workerLoop(int index) {
  long seen = 0;
  while (true) {
    std::unique_lock<std::mutex> lock(mutex_);
    start_.wait(lock, [&] { return stop_ || generation_ != seen; });
    if (stop_) return;
    seen = generation_;
    if (!bounds_) continue;  // a run this worker had no part in, already over
    const std::vector<long>& bounds = *bounds_;
    const auto& job = *job_;
    lock.unlock();
    if (index + 1 < static_cast<int>(bounds.size())) {
      try {
        job(index, bounds[index], bounds[index + 1]);
      } catch (...) {
        std::lock_guard<std::mutex> g(mutex_);
        if (!error_) error_ = std::current_exception();
      }
      std::lock_guard<std::mutex> g(mutex_);
      if (--pending_ == 0) done_.notify_one();
    }
  }
}

void ColumnWorkers::run(const std::vector<long>& bounds,
                        const std::function<void(int, long, long)>& job) {
  const int parts = static_cast<int>(bounds.size()) - 1;
  if (parts <= 0) return;
  if (parts == 1 || workers_.empty()) {
    for (int i = 0; i < parts; ++i) job(i, bounds[i], bounds[i + 1]);
    return;
  }
  std::lock_guard<std::mutex> serial(run_mutex_);
  const int helpers = std::min(parts - 1, static_cast<int>(workers_.size()));
  {
    std::lock_guard<std::mutex> lock(mutex_);
    bounds_ = &bounds;
    job_ = &job;
    pending_ = helpers;
    error_ = nullptr;
    ++generation_;
  }
  start_.notify_all();
  std::exception_ptr mine;
  try {
    job(0, bounds[0], bounds[1]);
    // Parts beyond the pool (more parts than threads) run here too.
    for (int i = helpers + 1; i < parts; ++i) job(i, bounds[i], bounds[i + 1]);
  } catch (...) {
    mine = std::current_exception();
  }
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, [&] { return pending_ == 0; });
  bounds_ = nullptr;
  job_ = nullptr;
  if (mine) std::rethrow_exception(mine);
  if (error_) std::rethrow_exception(error_);
}

std::vector<long> columnParts(long count, int threads, long min_columns, long align) {
  const long by_size = min_columns > 0 ? count / min_columns : count;
  const long parts = std::max<long>(1, std::min<long>(threads, by_size));
  std::vector<long> bounds{0};
  for (long i = 1; i < parts; ++i) {
    const long b = (count * i / parts) / align * align;
    if (b > bounds.back() && b < count) bounds.push_back(b);
  }
  bounds.push_back(count);
  return bounds;
}

}  // namespace pc_ekf
