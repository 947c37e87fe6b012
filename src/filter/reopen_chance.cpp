#include "pc_ekf/filter/reopen_chance.h"

#include <cmath>
#include <cstdint>
#include <map>
#include <mutex>
#include <stdexcept>
#include <tuple>
#include <vector>

#include "pc_ekf/filter/health.h"

namespace pc_ekf {
namespace {

// About 7 % relative error at 1e-3 per sample (200 events), in ~5 ms once
// per process; at lower rates the expected count matters little.
constexpr long kSamples = 200000;

// xoshiro256** (Blackman and Vigna), seeded by splitmix64: the simulation
// runs before the first sample of every process, and the standard library's
// engines and gamma variate made it the largest start-up cost.
class Xoshiro {
 public:
  explicit Xoshiro(std::uint64_t seed) {
    for (std::uint64_t& w : s_) {
      seed += 0x9e3779b97f4a7c15ULL;
      std::uint64_t z = seed;
      z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
      z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
      w = z ^ (z >> 31);
    }
  }
  // Uniform on (0, 1], so that its log is finite.
  double uniform() { return static_cast<double>((next() >> 11) + 1) * 0x1.0p-53; }
  // Standard normal: Marsaglia's polar method, one pair per accepted draw.
  double normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double a, b, r;
    do {
      a = 2.0 * uniform() - 1.0;
      b = 2.0 * uniform() - 1.0;
      r = a * a + b * b;
    } while (r >= 1.0);
    const double f = std::sqrt(-2.0 * std::log(r) / r);
    spare_ = b * f;
    has_spare_ = true;
    return a * f;
  }

 private:
  static std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  std::uint64_t next() {
    const std::uint64_t result = rotl(s_[1] * 5, 7) * 9;
    const std::uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return result;
  }
  std::uint64_t s_[4];
  double spare_ = 0.0;
  bool has_spare_ = false;
};

// chi2(1) = Z^2, chi2(2) = -2 log U, and from 3 dof 2 Gamma(dof / 2) by
// Marsaglia and Tsang's squeeze (one normal and one uniform per draw, about
// 98 % accepted), whatever dof is.
double chiSquare(Xoshiro& rng, int dof) {
  if (dof == 1) {
    const double z = rng.normal();
    return z * z;
  }
  if (dof == 2) return -2.0 * std::log(rng.uniform());
  const double d = dof / 2.0 - 1.0 / 3.0, c = 1.0 / std::sqrt(9.0 * d);
  for (;;) {
    double x, v;
    do {
      x = rng.normal();
      v = 1.0 + c * x;
    } while (v <= 0.0);
    v = v * v * v;
    const double u = rng.uniform(), x2 = x * x;
    if (u < 1.0 - 0.0331 * x2 * x2 || std::log(u) < 0.5 * x2 + d * (1.0 - v + std::log(v))) {
      return 2.0 * d * v;
    }
  }
}

double simulate(int window, int dof, double confidence, int after) {
  // The upper bound of the two-sided interval: only a window above it counts.
  const double tail = (1.0 - confidence) / 2.0;
  const double upper = chiSquareQuantile(1.0 - tail, static_cast<double>(window) * dof);
  Xoshiro rng(20261204);
  const auto chi2 = [&]() { return chiSquare(rng, dof); };
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

// simulate(20, dof, 0.99, 20) for dof = 1..24: the rule every shipped config
// with re-opens sets (test_filter_safeguard_rates recomputes each entry).
constexpr double kShippedRule[] = {
    0x1.a36e2eb1c432dp-16, 0x0p+0, 0x1.4f8b588e368f1p-18, 0x1.4f8b588e368f1p-18,
    0x1.4f8b588e368f1p-18, 0x1.4f8b588e368f1p-18, 0x1.4f8b588e368f1p-17, 0x1.4f8b588e368f1p-17,
    0x1.4f8b588e368f1p-17, 0x0p+0, 0x0p+0, 0x0p+0,
    0x0p+0, 0x0p+0, 0x0p+0, 0x0p+0,
    0x0p+0, 0x0p+0, 0x0p+0, 0x0p+0,
    0x0p+0, 0x0p+0, 0x0p+0, 0x0p+0};
constexpr int kShippedDof = static_cast<int>(sizeof kShippedRule / sizeof kShippedRule[0]);

void checkArguments(int window, int dof, double confidence, int after) {
  if (window < 1 || dof < 1 || after < 1 || !(confidence > 0.0 && confidence < 1.0)) {
    throw std::invalid_argument("chanceReopenPerSample: need window, dof, after >= 1 and 0 < confidence < 1");
  }
}

}  // namespace

double simulateChanceReopenPerSample(int window, int dof, double confidence, int after) {
  checkArguments(window, dof, confidence, after);
  return simulate(window, dof, confidence, after);
}

double chanceReopenPerSample(int window, int dof, double confidence, int after) {
  checkArguments(window, dof, confidence, after);
  if (window == 20 && confidence == 0.99 && after == 20 && dof <= kShippedDof) {
    return kShippedRule[dof - 1];
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
