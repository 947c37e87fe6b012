// Shared set-up of the benchmarks (test/benchmarks/bench_*.cpp): the paper's
// speed-bump configuration from config/speed_bump.yaml, synthetic data, and
// latency statistics. Figures go out as Google Benchmark user counters, which
// launch_free_scripts/bench.sh collects into results/bench.json.
#pragma once

#include <benchmark/benchmark.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "pc_ekf/filter/one_step_filter.h"
#include "pc_ekf/filter/pc_propagator.h"
#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/io/estimator_config.h"

namespace pc_ekf::bench {

inline std::string configPath(const std::string& name = "speed_bump.yaml") {
  return std::string(PC_EKF_SOURCE_DIR) + "/config/" + name;
}

// Integration settings of a benchmark: as config/speed_bump.yaml has them
// (kConfigured), or one of the two points of the accuracy/cost curve that
// matter: the classical RK4 at 1 ms (the foundation's default) and the
// fixed-step Dormand-Prince 5 at 3 ms (half the evaluations, half the error).
enum class Integration { kConfigured = 0, kRk4At1ms = 1, kDp5At3ms = 2 };
inline const char* label(Integration i) {
  return i == Integration::kConfigured ? "config" : i == Integration::kRk4At1ms ? "rk4_1ms" : "dp5_3ms";
}
inline void applyIntegration(EstimatorConfig& c, Integration i) {
  if (i == Integration::kRk4At1ms) c.integration = IntegratorSettings{1e-3, IntegrationMethod::kRk4};
  if (i == Integration::kDp5At3ms) {
    c.integration = IntegratorSettings{3e-3, IntegrationMethod::kDormandPrince5};
  }
}

// The paper's configuration (n = 2, p = 4, S = 15, Q = 30, speed bump) with N samples over 3 s.
inline EstimatorConfig paperConfig(int samples, Integration integration = Integration::kConfigured) {
  EstimatorConfig c = loadConfigFile(configPath());
  c.sampling.samples = samples;
  applyIntegration(c, integration);
  return c;
}

// Roll-plane parameters declared uncertain beyond M and d_CG (+-10 %, truth at
// xi = 0.1), in this order, for n = 3..8 uncertain parameters.
inline std::vector<std::string> extraUncertainNames(int n) {
  static const std::vector<std::string> names = {"spring_linear_left",  "spring_linear_right",
                                                 "damping_left",        "damping_right",
                                                 "tyre_stiffness_left", "tyre_stiffness_right"};
  return {names.begin(), names.begin() + std::max(0, std::min<int>(n - 2, names.size()))};
}

// The paper's case with n uncertain parameters, PC order p and a design:
// kSmolyak takes `count` as its level, kGauss as nodes per germ, the others as Q.
inline EstimatorConfig manyParameterConfig(int n, int p, PointSequence sequence, int count,
                                           int threads = 1, int samples = 100) {
  EstimatorConfig c = withUncertain(paperConfig(samples), extraUncertainNames(n), 0.1, 0.1);
  c.pc_order = p;
  c.collocation.sequence = sequence;
  c.collocation.points = count;
  c.collocation.level = count;
  c.collocation.threads = threads;
  return c;
}

// The many-parameter table's hyperbolic-cross row: n = 8, p = 4, q = 0.5
// (S = 61 instead of 495 terms), Q = 2S Halton points.
inline EstimatorConfig hyperbolicConfig(int n, int threads = 1, int samples = 100) {
  const BasisTruncation t{TruncationKind::kHyperbolic, 0.5};
  const int s = static_cast<int>(truncatedMultiIndices(n, 4, t).size());
  EstimatorConfig c = manyParameterConfig(n, 4, PointSequence::kHalton, 2 * s, threads, samples);
  c.pc_truncation = t;
  return c;
}

// Order p of the scaling table per number n of uncertain parameters: the
// highest whose sparse grid (level p, exact to degree 2p + 1) keeps the
// one-step update far above real time on two cores.
inline int scalingOrder(int n) { return n <= 2 ? 4 : n == 3 ? 3 : 2; }

// S = C(n + p, p).
inline int basisTerms(int n, int p) {
  long r = 1;
  for (int i = 1; i <= p; ++i) r = r * (n + i) / i;
  return static_cast<int>(r);
}

struct Scenario {
  EstimatorConfig config;
  std::shared_ptr<const MechanicalModel> model;
  std::shared_ptr<const PcPropagator> propagator;
  MeasurementSeries series;
};

inline Scenario makeScenario(const EstimatorConfig& c, std::uint64_t seed = 1) {
  Scenario s;
  s.config = c;
  s.model = makeModel(c, makeRoad(c));
  s.propagator = makePropagator(c, s.model);
  s.series = synthesizeFromConfig(c, *s.model, seed);
  return s;
}

// Wall-clock and this thread's CPU clock, in seconds.
inline double wallSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
inline double threadCpuSeconds() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}
inline double processCpuSeconds() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// q-quantile (0..1) by nearest rank of a copy.
inline double quantile(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const auto i = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
  return v[std::min(v.size() - 1, i == 0 ? 0 : i - 1)];
}

// Best (smallest) of repeated timings of f(): robust against other processes
// on the machine (they only ever make a run slower).
template <typename F>
double bestOf(int repeats, F&& f, double (*clock)() = threadCpuSeconds) {
  double best = INFINITY;
  for (int r = 0; r < repeats; ++r) {
    const double start = clock();
    f();
    best = std::min(best, clock() - start);
  }
  return best;
}

}  // namespace pc_ekf::bench
