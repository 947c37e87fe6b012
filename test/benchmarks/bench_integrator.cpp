// The model's right-hand side and the RK4 integrator: cost of one
// derivative evaluation per point, of one 0.03 s forecast interval for the 30
// collocation points, and the accuracy/cost curve that chose the default
// integration.max_step: error of the sampled channels (N = 100 sample times,
// as the filters integrate) against a 1/32 ms reference, relative to each
// channel's range and to the 1 % measurement noise.
#include <random>

#include "bench_support.h"
#include "pc_ekf/model/integrator.h"

namespace pc_ekf::bench {
namespace {

Eigen::MatrixXd collocationParameters(const Scenario& s) {
  const PcPropagator& p = *s.propagator;
  return p.parametersAtPoints(p.priorState().bottomRows(p.parameterCount()), nullptr);
}

// ns per point for one right-hand-side evaluation (structure-of-arrays path).
void BM_RightHandSide(benchmark::State& state) {
  const Scenario s = makeScenario(paperConfig(100));
  const int q = static_cast<int>(state.range(0));
  const Eigen::MatrixXd colloc = collocationParameters(s);
  Eigen::MatrixXd params(colloc.rows(), q);
  for (int i = 0; i < q; ++i) params.col(i) = colloc.col(i % colloc.cols());
  const auto batch = s.model->prepare(params);
  std::mt19937_64 rng(1);
  std::normal_distribution<double> n(0.0, 0.02);
  Eigen::ArrayXXd y(q, 8), d(q, 8);
  for (Eigen::Index i = 0; i < y.size(); ++i) y(i) = n(rng);
  for (auto _ : state) {
    batch->derivativesTransposed(0.2, y, d);
    benchmark::DoNotOptimize(d.data());
    benchmark::ClobberMemory();
  }
  state.counters["points"] = q;  // CPU time / points = time per point
}
BENCHMARK(BM_RightHandSide)->Arg(1)->Arg(30)->Arg(1024);

// One 0.03 s interval of the 30 collocation points (the one-step forecast's
// integration), CPU time per interval: RK4 at 1 ms and Dormand-Prince 5 at 3 ms.
void BM_Rk4Interval(benchmark::State& state) {
  const Scenario s = makeScenario(paperConfig(100));
  const auto batch = s.model->prepare(collocationParameters(s));
  IntegratorSettings settings;
  settings.max_step = 1e-6 * static_cast<double>(state.range(0));
  settings.method = static_cast<IntegrationMethod>(state.range(1));
  Eigen::ArrayXXd y = batch->initialState();
  double t = 0.0;
  for (auto _ : state) {
    if (t > 2.9) {
      y = batch->initialState();
      t = 0.0;
    }
    integrate(*s.model, *batch, t, t + 0.03, y, settings);
    t += 0.03;
    benchmark::DoNotOptimize(y.data());
  }
  if (!y.allFinite()) state.SkipWithError("the integration is not finite");
  state.counters["max_step_ms"] = 1e3 * settings.max_step;
}
BENCHMARK(BM_Rk4Interval)->Args({1000, 0})->Args({3000, 1})->Unit(benchmark::kMicrosecond);

// Channels at the N = 100 sample times, integrating sample to sample as the filters do.
Eigen::MatrixXd sampledChannels(const Scenario& s, const ModelBatch& batch,
                                const IntegratorSettings& settings) {
  Eigen::ArrayXXd y = batch.initialState();
  const int n = s.config.sampling.samples;
  Eigen::MatrixXd z(4 * n, batch.pointCount());
  double t = 0.0;
  for (int k = 0; k < n; ++k) {
    const double t1 = s.series[k].time;
    integrate(*s.model, batch, t, t1, y, settings);
    t = t1;
    z.middleRows(4 * k, 4) = (s.model->observationMatrix() * y.matrix()).topRows(4);
  }
  return z;
}

// Accuracy/cost curve: worst error over the 30 points, 4 channels and 100
// samples, (a) relative to the channel's range over the record, (b) relative
// to the measurement noise std 0.01 |z| at that sample (floored at 1e-3 of the
// range, so zero crossings do not divide by ~0); and CPU time per 0.03 s.
void BM_StepAccuracy(benchmark::State& state) {
  const Scenario s = makeScenario(paperConfig(100));
  const auto batch = s.model->prepare(collocationParameters(s));
  IntegratorSettings settings;
  settings.max_step = 1e-6 * static_cast<double>(state.range(0));
  settings.method = static_cast<IntegrationMethod>(state.range(1));
  static const Eigen::MatrixXd reference =
      sampledChannels(s, *batch, IntegratorSettings{1e-3 / 32, IntegrationMethod::kDormandPrince5});
  Eigen::MatrixXd z;
  for (auto _ : state) z = sampledChannels(s, *batch, settings);
  double worst_range = 0.0, worst_noise = 0.0;
  for (int c = 0; c < 4; ++c) {
    for (int q = 0; q < batch->pointCount(); ++q) {
      double range = 0.0;
      for (int k = 0; k < 100; ++k) range = std::max(range, std::abs(reference(4 * k + c, q)));
      for (int k = 0; k < 100; ++k) {
        const double e = std::abs(z(4 * k + c, q) - reference(4 * k + c, q));
        worst_range = std::max(worst_range, e / range);
        const double noise = std::max(0.01 * std::abs(reference(4 * k + c, q)), 1e-3 * range);
        worst_noise = std::max(worst_noise, e / noise);
      }
    }
  }
  const double cpu = bestOf(5, [&] { z = sampledChannels(s, *batch, settings); });
  state.counters["max_step_ms"] = 1e3 * settings.max_step;
  state.counters["dp5"] = static_cast<double>(state.range(1));
  state.counters["error_rel_range"] = worst_range;
  state.counters["error_rel_noise"] = worst_noise;
  state.counters["us_per_interval"] = 1e6 * cpu / 100.0;
}
BENCHMARK(BM_StepAccuracy)
    ->ArgsProduct({{500, 1000, 1500, 2000, 3000, 4000, 5000, 7500, 10000}, {0, 1}})
    ->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace pc_ekf::bench

BENCHMARK_MAIN();
