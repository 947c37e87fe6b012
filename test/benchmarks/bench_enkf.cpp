// PC-EKF vs Monte-Carlo EnKF on filtering: over 10 noise seeds of
// the paper's cases A (N = 10) and B (N = 100), the error of each filter's
// final parameter means against the exact posterior (docs/method.md §4.6; coarse-grid
// simulations shared across seeds through CoarseGridCache):
//   error = RMS over seeds and both parameters of (mean - posterior mean) / posterior std.
// The benchmark finds the smallest EnKF ensemble (perturbed observations, the
// baseline of docs/method.md §4.7; 2 ensemble seeds per noise seed, enkf.seed + 100 e + noise
// seed) whose error is no worse than the square-root PC-EKF's, per case and
// in both, and reports the ratios EnKF / PC-EKF of CPU time (both on one
// thread) and of model integrations (member- or point-intervals) at that size.
#include <algorithm>

#include "bench_support.h"
#include "pc_ekf/filter/ensemble_kalman_filter.h"
#include "pc_ekf/reference/reference_posterior.h"
#include "pc_ekf/filter/trajectory_simulation.h"

namespace pc_ekf::bench {
namespace {

constexpr int kSeeds = 10;
constexpr int kEnsembleSeeds = 2;  // per noise seed: averages out the EnKF's own sampling
const std::vector<int> kMembers = {25, 50, 100, 200, 400, 800, 1600};

struct FilterRun {
  Eigen::VectorXd mean;
  double cpu = 0.0;
  long integrations = 0;
};

FilterRun runPc(const Scenario& s, const MeasurementSeries& data) {
  FilterRun r;
  const auto prop = makePropagator(s.config, s.model);  // fresh integration count
  OneStepFilter f(prop, makeOneStepSettings(s.config));
  const double c0 = threadCpuSeconds();
  StepResult last;
  for (const Measurement& m : data) last = f.process(m);
  r.cpu = threadCpuSeconds() - c0;
  r.mean = last.mean;
  r.integrations = prop->integrations();
  return r;
}

FilterRun runEnkf(const Scenario& s, const MeasurementSeries& data, int members,
                  std::uint64_t seed) {
  FilterRun r;
  EnkfSettings settings = makeEnkfSettings(s.config);
  settings.members = members;
  settings.seed = s.config.enkf.seed + seed;
  settings.threads = 1;  // CPU time comparable with the one-thread PC-EKF
  EnsembleKalmanFilter f(s.model, ParameterMapping(*s.model, s.config.uncertain), settings);
  const double c0 = threadCpuSeconds();
  EnkfStep last;
  for (const Measurement& m : data) last = f.process(m);
  r.cpu = threadCpuSeconds() - c0;
  r.mean = last.mean;
  r.integrations = f.integrations();
  return r;
}

struct CaseResult {
  double pc_error = 0.0, pc_cpu = 0.0;
  long pc_integrations = 0;
  std::vector<double> enkf_error, enkf_cpu, enkf_integrations;  // per ensemble size
  double posterior_seconds = 0.0;
};

double squaredError(const Eigen::VectorXd& mean, const ReferencePosterior& ref) {
  return ((mean - ref.mean).array() / ref.stddev.array()).square().sum();
}

CaseResult runCase(int samples) {
  const Scenario s = makeScenario(paperConfig(samples));
  const ParameterMapping mapping(*s.model, s.config.uncertain);
  ReferencePosteriorSettings ps = makeReferenceSettings(s.config);
  ps.threads = 2;
  const CoarseGridCache cache(*s.model, mapping, sampleTimes(s.series), s.config.integration,
                              ps.coarse_points, ps.threads);
  CaseResult out;
  out.enkf_error.assign(kMembers.size(), 0.0);
  out.enkf_cpu.assign(kMembers.size(), 0.0);
  out.enkf_integrations.assign(kMembers.size(), 0.0);
  const double count = 2.0 * kSeeds;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    const MeasurementSeries data = synthesizeFromConfig(s.config, *s.model, seed);
    const double p0 = wallSeconds();
    const ReferencePosterior ref = computeReferencePosterior(
        *s.model, mapping, data, s.config.measurement.noise, s.config.integration, ps, &cache);
    out.posterior_seconds += wallSeconds() - p0;
    const FilterRun pc = runPc(s, data);
    out.pc_error += squaredError(pc.mean, ref) / count;
    out.pc_cpu += pc.cpu / kSeeds;
    out.pc_integrations = pc.integrations;
    for (std::size_t i = 0; i < kMembers.size(); ++i) {
      for (int es = 0; es < kEnsembleSeeds; ++es) {
        const FilterRun e = runEnkf(s, data, kMembers[i], static_cast<std::uint64_t>(seed + 100 * es));
        out.enkf_error[i] += squaredError(e.mean, ref) / (count * kEnsembleSeeds);
        out.enkf_cpu[i] += e.cpu / (kSeeds * kEnsembleSeeds);
        out.enkf_integrations[i] = static_cast<double>(e.integrations);
      }
    }
  }
  out.pc_error = std::sqrt(out.pc_error);
  for (double& e : out.enkf_error) e = std::sqrt(e);
  return out;
}

void BM_EnkfEqualAccuracy(benchmark::State& state) {
  CaseResult a, b;
  for (auto _ : state) {
    a = runCase(10);
    b = runCase(100);
  }
  // Smallest tested size whose error is no worse than the PC-EKF's (-1: none).
  const auto smallest = [](const CaseResult& c) {
    for (std::size_t i = 0; i < kMembers.size(); ++i) {
      if (c.enkf_error[i] <= c.pc_error) return static_cast<int>(i);
    }
    return -1;
  };
  const int match_a = smallest(a), match_b = smallest(b);
  state.counters["seeds"] = kSeeds;
  state.counters["ensemble_seeds"] = kEnsembleSeeds;
  state.counters["largest_members"] = kMembers.back();
  state.counters["pc_error_A"] = a.pc_error;
  state.counters["pc_error_B"] = b.pc_error;
  state.counters["pc_cpu_A_s"] = a.pc_cpu;
  state.counters["pc_cpu_B_s"] = b.pc_cpu;
  state.counters["enkf_best_error_A"] = *std::min_element(a.enkf_error.begin(), a.enkf_error.end());
  state.counters["enkf_best_error_B"] = *std::min_element(b.enkf_error.begin(), b.enkf_error.end());
  for (std::size_t i = 0; i < kMembers.size(); ++i) {
    const std::string m = std::to_string(kMembers[i]);
    state.counters["enkf_error_A_" + m] = a.enkf_error[i];
    state.counters["enkf_error_B_" + m] = b.enkf_error[i];
    state.counters["enkf_cpu_A_" + m + "_s"] = a.enkf_cpu[i];
    state.counters["enkf_cpu_B_" + m + "_s"] = b.enkf_cpu[i];
  }
  const auto ratios = [&](const CaseResult& c, int at, const std::string& suffix) {
    state.counters["equal_accuracy_members" + suffix] = at < 0 ? -1 : kMembers[at];
    state.counters["wall_ratio" + suffix] = at < 0 ? -1 : c.enkf_cpu[at] / c.pc_cpu;
    state.counters["integration_ratio" + suffix] =
        at < 0 ? -1 : c.enkf_integrations[at] / static_cast<double>(c.pc_integrations);
  };
  ratios(a, match_a, "_A");
  ratios(b, match_b, "_B");
  // Both cases: the larger of the two sizes; ratios summed over the cases.
  const int both = match_a < 0 || match_b < 0 ? -1 : std::max(match_a, match_b);
  state.counters["equal_accuracy_members"] = both < 0 ? -1 : kMembers[both];
  state.counters["wall_ratio"] =
      both < 0 ? -1 : (a.enkf_cpu[both] + b.enkf_cpu[both]) / (a.pc_cpu + b.pc_cpu);
  state.counters["integration_ratio"] =
      both < 0 ? -1 : (a.enkf_integrations[both] + b.enkf_integrations[both]) /
                          static_cast<double>(a.pc_integrations + b.pc_integrations);
}
BENCHMARK(BM_EnkfEqualAccuracy)->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace
}  // namespace pc_ekf::bench

BENCHMARK_MAIN();
