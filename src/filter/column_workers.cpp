#include "pc_ekf/filter/column_workers.h"

#include <algorithm>
#include <chrono>

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

}  // namespace

int ColumnWorkers::defaultThreads() {
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

ColumnWorkers::ColumnWorkers(int threads) : threads_(threads <= 0 ? defaultThreads() : threads) {
  for (int i = 1; i < threads_; ++i) workers_.emplace_back([this, i] { workerLoop(i); });
}

ColumnWorkers::~ColumnWorkers() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_.store(true);
  }
  start_.notify_all();
  for (auto& w : workers_) w.join();
}

void ColumnWorkers::workerLoop(int index) {
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
    // Every worker takes part in every run (an empty part when there are
    // fewer parts than threads), so none reads a finished run's job.
    const long begin = begins_[index], end = ends_[index];
    if (end > begin) {
      try {
        (*job_)(index, begin, end);
      } catch (...) {
        std::lock_guard<std::mutex> g(mutex_);
        if (!error_) error_ = std::current_exception();
      }
    }
    if (pending_.fetch_sub(1, std::memory_order_acq_rel) == 1) {
      std::lock_guard<std::mutex> g(mutex_);
      done_.notify_one();
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
  const int helpers = static_cast<int>(workers_.size());
  begins_.assign(helpers + 1, 0);
  ends_.assign(helpers + 1, 0);
  for (int i = 1; i <= helpers && i < parts; ++i) {
    begins_[i] = bounds[i];
    ends_[i] = bounds[i + 1];
  }
  job_ = &job;
  error_ = nullptr;
  pending_.store(helpers, std::memory_order_relaxed);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    generation_.fetch_add(1, std::memory_order_release);
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
  if (!spinUntil([&] { return pending_.load(std::memory_order_acquire) == 0; })) {
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [&] { return pending_.load() == 0; });
  }
  job_ = nullptr;
  if (mine) std::rethrow_exception(mine);
  std::lock_guard<std::mutex> lock(mutex_);
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
