// Work split among threads in contiguous parts.
#pragma once

#include <algorithm>
#include <thread>
#include <vector>

namespace pc_ekf {

// job(part, begin, end) over [0, count) in `threads` contiguous parts, the
// first on the calling thread, the others on threads of their own (joined
// before it returns). Parts must write disjoint outputs; the job must not
// throw on a helper thread (that ends the process): check inputs before.
template <typename Job>
void inNumberedParts(int count, int threads, const Job& job) {
  const int parts = std::max(1, std::min(threads, count));
  std::vector<std::thread> helpers;
  for (int t = 1; t < parts; ++t) {
    helpers.emplace_back([&job, t, parts, count] { job(t, count * t / parts, count * (t + 1) / parts); });
  }
  job(0, 0, count / parts);
  for (std::thread& h : helpers) h.join();
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
