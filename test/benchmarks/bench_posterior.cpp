// Reference posterior (docs/method.md §4.6) for the paper's case B (N = 100, seed 1):
// coarse 101^2 grid of full simulations + Levenberg-Marquardt + fine
// principal-axis grids, on both cores (grid.threads = 2). Wall time.
#include "bench_support.h"
#include "pc_ekf/reference/reference_posterior.h"

namespace pc_ekf::bench {
namespace {

void referencePosterior(benchmark::State& state, const Scenario& s) {
  const ParameterMapping mapping(*s.model, s.config.uncertain);
  ReferencePosteriorSettings ps = makeReferenceSettings(s.config);
  ps.threads = static_cast<int>(state.range(0));
  ReferencePosterior p;
  double wall = 0.0, cpu = 0.0;
  for (auto _ : state) {
    const double w0 = wallSeconds(), c0 = processCpuSeconds();
    p = computeReferencePosterior(*s.model, mapping, s.series, s.config.measurement.noise,
                                  s.config.integration, ps);
    wall = wallSeconds() - w0;
    cpu = processCpuSeconds() - c0;
  }
  state.counters["threads"] = ps.threads;
  state.counters["wall_s"] = wall;
  state.counters["cpu_s"] = cpu;
  state.counters["simulations"] = static_cast<double>(p.simulations);
  state.counters["coarse_s"] = p.coarse_seconds;
  state.counters["refine_s"] = p.refine_seconds;
  state.counters["fine_s"] = p.fine_seconds;
  state.counters["modes"] = static_cast<double>(p.modes.size());
  state.counters["border_mass"] = p.border_mass;
}
void BM_ReferencePosteriorCaseB(benchmark::State& state) {
  referencePosterior(state, makeScenario(paperConfig(100)));
}
BENCHMARK(BM_ReferencePosteriorCaseB)->Arg(2)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

// The full car (config/full_car_bump.yaml: n = 3, N = 100): the posterior in three dimensions.
void BM_ReferencePosteriorFullCar(benchmark::State& state) {
  referencePosterior(state, makeScenario(loadConfigFile(configPath("full_car_bump.yaml"))));
}
BENCHMARK(BM_ReferencePosteriorFullCar)->Arg(2)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

}  // namespace
}  // namespace pc_ekf::bench

BENCHMARK_MAIN();
