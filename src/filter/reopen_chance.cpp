#include "pc_ekf/filter/reopen_chance.h"

#include <cmath>
#include <map>
#include <mutex>
#include <random>
#include <stdexcept>
#include <tuple>
#include <vector>

#include "pc_ekf/filter/health.h"

namespace pc_ekf {
namespace {

// About 7 % relative error at 1e-3 per sample (200 events), in ~20 ms once
// per process; at lower rates the expected count matters little.
constexpr long kSamples = 200000;

double simulate(int window, int dof, double confidence, int after) {
  // The upper bound of the two-sided interval: only a window above it counts.
  const double tail = (1.0 - confidence) / 2.0;
  const double upper = chiSquareQuantile(1.0 - tail, static_cast<double>(window) * dof);
  // chi2(dof): 1 and 2 dof in their direct forms (Z^2, -2 log U), several
  // times cheaper than a gamma variate; more as 2 Gamma(dof / 2), one draw
  // whatever dof is (this runs before the first sample of every process).
  std::mt19937_64 rng(20261204);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> normal;
  std::gamma_distribution<double> half_chi2(dof / 2.0, 2.0);
  const auto chi2 = [&]() {
    if (dof == 1) {
      const double z = normal(rng);
      return z * z;
    }
    if (dof == 2) return -2.0 * std::log(1.0 - uniform(rng));  // 1 - U is in (0, 1]
    return half_chi2(rng);
  };
  std::vector<double> ring(static_cast<std::size_t>(window));
  int filled = 0;
  double sum = 0.0;
  long reopens = 0;
  int violations = 0;
  for (long k = 0; k < kSamples; ++k) {
    const double x = chi2();
    double& slot = ring[static_cast<std::size_t>(k % window)];
    if (filled == window) {
      sum -= slot;
    } else {
      ++filled;
    }
    slot = x;
    sum += x;
    const bool outside = filled == window && sum > upper;
    violations = outside ? violations + 1 : 0;
    if (violations >= after) {
      ++reopens;
      violations = 0;
      filled = 0;
      sum = 0.0;
    }
  }
  return static_cast<double>(reopens) / static_cast<double>(kSamples);
}

}  // namespace

double chanceReopenPerSample(int window, int dof, double confidence, int after) {
  if (window < 1 || dof < 1 || after < 1 || !(confidence > 0.0 && confidence < 1.0)) {
    throw std::invalid_argument("chanceReopenPerSample: need window, dof, after >= 1 and 0 < confidence < 1");
  }
  static std::mutex mutex;
  static std::map<std::tuple<int, int, double, int>, double> cache;
  const auto key = std::make_tuple(window, dof, confidence, after);
  {
    std::lock_guard<std::mutex> lock(mutex);
    const auto it = cache.find(key);
    if (it != cache.end()) return it->second;
  }
  const double p = simulate(window, dof, confidence, after);
  std::lock_guard<std::mutex> lock(mutex);
  return cache.emplace(key, p).first->second;
}

}  // namespace pc_ekf
