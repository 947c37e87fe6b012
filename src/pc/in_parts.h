// Work split among threads in contiguous parts.
#pragma once

#include <algorithm>
#include <exception>
#include <thread>
#include <vector>

namespace pc_ekf {

// job(part, begin, end) over [0, count) in `threads` contiguous parts, the
// first on the calling thread, the others on threads of their own (joined
// before it returns). Parts must write disjoint outputs. An exception thrown
// by a part is thrown again here once every part has ended (the first one,
// in part order).
template <typename Job>
void inNumberedParts(int count, int threads, const Job& job) {
  const int parts = std::max(1, std::min(threads, count));
  std::vector<std::exception_ptr> errors(static_cast<std::size_t>(parts));
  std::vector<std::thread> helpers;
  for (int t = 1; t < parts; ++t) {
    helpers.emplace_back([&job, &errors, t, parts, count] {
      try {
        job(t, count * t / parts, count * (t + 1) / parts);
      } catch (...) {
        errors[static_cast<std::size_t>(t)] = std::current_exception();
      }
    });
  }
  try {
    job(0, 0, count / parts);
  } catch (...) {
    errors[0] = std::current_exception();
  }
  for (std::thread& h : helpers) h.join();
  for (const std::exception_ptr& e : errors) {
    if (e) std::rethrow_exception(e);
  }
}

// The same, job(begin, end).
template <typename Job>
void inParts(int count, int threads, const Job& job) {
  inNumberedParts(count, threads, [&job](int, int begin, int end) { job(begin, end); });
}

// The machine's hardware threads (1 when it does not say).
inline int machineThreads() {
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

}  // namespace pc_ekf
