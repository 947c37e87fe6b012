#include "pc_ekf/filter/column_workers.h"

#include <algorithm>
#include <chrono>

#include "pc_ekf/pc/in_parts.h"

namespace pc_ekf {

namespace {

// Spin this long before sleeping: a forecast part lasts tens of
// microseconds, a futex wake-up costs about as much. Longer spins only take
// the core from other processes when the machine is busy.
constexpr std::chrono::microseconds kSpin{30};

// Spins until done() or kSpin has passed; true when done.
template <typename Done>
bool spinUntil(Done&& done) {
  const auto deadline = std::chrono::steady_clock::now() + kSpin;
  while (!done()) {
    for (int i = 0; i < 32; ++i) {
#if defined(__x86_64__) || defined(__i386__)
      __builtin_ia32_pause();
#endif
    }
    if (std::chrono::steady_clock::now() > deadline) return done();
  }
  return true;
}

constexpr int kIndexBits = 20;
constexpr long kIndexMask = (1L << kIndexBits) - 1;

}  // namespace

int ColumnWorkers::defaultThreads() { return machineThreads(); }

ColumnWorkers::ColumnWorkers(int threads) : threads_(threads <= 0 ? defaultThreads() : threads) {
  for (int i = 1; i < threads_; ++i) workers_.emplace_back([this] { workerLoop(); });
}

ColumnWorkers::~ColumnWorkers() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_.store(true);
  }
  start_.notify_all();
  for (auto& w : workers_) w.join();
}

bool ColumnWorkers::runClaimedParts(long generation) {
  bool any = false;
  while (true) {
    // Claim the next part of this generation only (a compare-exchange, so a
    // late worker never touches a later run's counter).
    long c = next_.load(std::memory_order_acquire);
    long part = 0;
    do {
      part = c & kIndexMask;
      if ((c >> kIndexBits) != generation || part >= parts_) return any;
    } while (!next_.compare_exchange_weak(c, c + 1, std::memory_order_acq_rel));
    // The run cannot finish before this claimed part is done: its data is stable.
    any = true;
    try {
      (*job_)(static_cast<int>(part), bounds_[part], bounds_[part + 1]);
    } catch (...) {
      std::lock_guard<std::mutex> g(mutex_);
      if (!error_) error_ = std::current_exception();
    }
    if (done_parts_.fetch_add(1, std::memory_order_acq_rel) + 1 == parts_) {
      std::lock_guard<std::mutex> g(mutex_);
      done_.notify_one();
    }
  }
}

void ColumnWorkers::workerLoop() {
  long seen = 0;
  while (true) {
    if (!spinUntil([&] {
          return generation_.load(std::memory_order_acquire) != seen ||
                 stop_.load(std::memory_order_relaxed);
        })) {
      std::unique_lock<std::mutex> lock(mutex_);
      start_.wait(lock, [&] { return stop_.load() || generation_.load() != seen; });
    }
    if (stop_.load()) return;
    seen = generation_.load(std::memory_order_acquire);
    runClaimedParts(seen);
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
  // Parts are claimed by whoever is free: a worker the scheduler wakes late
  // (a busy machine) leaves its parts to this thread instead of stalling it.
  const long generation = generation_.load(std::memory_order_relaxed) + 1;
  bounds_ = bounds;
  job_ = &job;
  parts_ = parts;
  error_ = nullptr;
  done_parts_.store(0, std::memory_order_relaxed);
  next_.store(generation << kIndexBits, std::memory_order_release);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    generation_.store(generation, std::memory_order_release);
  }
  start_.notify_all();
  runClaimedParts(generation);
  if (!spinUntil([&] { return done_parts_.load(std::memory_order_acquire) == parts; })) {
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [&] { return done_parts_.load() == parts; });
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (error_) std::rethrow_exception(error_);
}

std::vector<long> columnParts(long count, int parts, long min_columns, long align) {
  const long by_size = min_columns > 0 ? count / min_columns : count;
  const long n = std::max<long>(1, std::min<long>(parts, by_size));
  std::vector<long> bounds{0};
  for (long i = 1; i < n; ++i) {
    const long b = (count * i / n) / align * align;
    if (b > bounds.back() && b < count) bounds.push_back(b);
  }
  bounds.push_back(count);
  return bounds;
}

}  // namespace pc_ekf
