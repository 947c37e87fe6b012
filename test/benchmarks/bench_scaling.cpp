// Scaling: cost of one one-step update (forecast over dt = 0.03 s +
// square-root update + health) for PC order p = 2..8 and n = 2..4 uncertain
// parameters (Table I: + spring_linear_left, + tyre_stiffness_left), Q = 2S;
// and the whole-set update for N = 10^2..10^5 samples over the 3 s record,
// split into the forecast (simulating the Q collocation points through all
// sample times) and what comes after it (stacking, projection, Kalman update).
#include "bench_support.h"
#include "pc_ekf/filter/batch_update.h"
#include "pc_ekf/filter/trajectory_simulation.h"

namespace pc_ekf::bench {
namespace {

EstimatorConfig scalingConfig(int n, int p) {
  EstimatorConfig c = paperConfig(100);
  const char* extra[] = {"spring_linear_left", "tyre_stiffness_left"};
  const ParameterTable& table = c.model_type->description().parameters();
  const double nominal[] = {c.model->values[table.at(extra[0])],
                            c.model->values[table.at(extra[1])]};
  for (int i = 2; i < n; ++i) {
    UncertainParameter u = c.uncertain.front();
    u.name = extra[i - 2];
    u.nominal = nominal[i - 2];
    u.relative_range = 0.1;
    c.uncertain.push_back(u);
    c.truth.xi.push_back(0.1);
  }
  c.pc_order = p;
  const long s = [&] {  // C(n + p, p)
    long r = 1;
    for (int i = 1; i <= p; ++i) r = r * (n + i) / i;
    return r;
  }();
  c.collocation.points = static_cast<int>(2 * s);
  return c;
}

// Per sample of the first `samples`, the best over `passes` runs of the
// one-step filter from the prior of the time `clock` measures for its update.
std::vector<double> bestStepTimes(const Scenario& s, int samples, int passes, double (*clock)()) {
  OneStepFilter filter(s.propagator, makeOneStepSettings(s.config));
  std::vector<double> best(samples, INFINITY);
  for (int pass = 0; pass < passes; ++pass) {
    filter.reset();
    for (int k = 0; k < samples; ++k) {
      const double t0 = clock();
      const StepResult r = filter.process(s.series[k]);
      best[k] = std::min(best[k], clock() - t0);
      benchmark::DoNotOptimize(r.mean.data());
    }
  }
  return best;
}

// Median and p99 over the samples of the best-of-passes CPU time per update.
void BM_UpdateScaling(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0)), p = static_cast<int>(state.range(1));
  const Scenario s = makeScenario(scalingConfig(n, p));
  const int samples = 20;  // the first 0.6 s: the bump, the expensive part
  const int passes = s.propagator->termCount() > 200 ? 2 : 5;
  std::vector<double> best;
  for (auto _ : state) best = bestStepTimes(s, samples, passes, threadCpuSeconds);
  state.counters["n"] = n;
  state.counters["p"] = p;
  state.counters["S"] = s.propagator->termCount();
  state.counters["Q"] = s.propagator->design().pointCount();
  state.counters["median_us"] = 1e6 * quantile(best, 0.5);
  state.counters["p99_us"] = 1e6 * quantile(best, 0.99);
}
BENCHMARK(BM_UpdateScaling)
    ->ArgsProduct({{2, 3, 4}, {2, 3, 4, 5, 6, 7, 8}})
    ->Iterations(1)->Unit(benchmark::kMillisecond);

// One-step update (square root, dt = 0.03 s, the bump's first 0.6 s) with n
// uncertain roll-plane parameters (bench_support.h), p = scalingOrder(n), on
// `threads` threads. Design 0: Smolyak sparse grid of level p (least squares
// on its nodes, the default projection); 1: Q = 2S Halton points; 2: p = 4,
// hyperbolic cross q = 0.5, Q = 2S Halton points. Wall time per sample
// (the workers' time counts), best of the passes, median over the samples.
void BM_ManyParameters(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0)), threads = static_cast<int>(state.range(1));
  const bool halton = state.range(2) >= 1, hyperbolic = state.range(2) == 2;
  const int p = hyperbolic ? 4 : scalingOrder(n);
  const EstimatorConfig c =
      hyperbolic ? hyperbolicConfig(n, threads)
      : halton   ? manyParameterConfig(n, p, PointSequence::kHalton, 2 * basisTerms(n, p), threads)
                 : manyParameterConfig(n, p, PointSequence::kSmolyak, p, threads);
  const Scenario s = makeScenario(c);
  const int samples = 20;
  std::vector<double> best;
  for (auto _ : state) best = bestStepTimes(s, samples, 8, wallSeconds);
  const double dt = s.config.sampling.duration / s.config.sampling.samples;
  state.counters["n"] = n;
  state.counters["p"] = p;
  state.counters["S"] = s.propagator->termCount();
  state.counters["Q"] = s.propagator->design().pointCount();
  state.counters["smolyak"] = halton ? 0 : 1;
  state.counters["q_norm"] = c.pc_truncation.q_norm;
  state.counters["threads"] = s.propagator->threads();
  state.counters["median_us"] = 1e6 * quantile(best, 0.5);
  state.counters["p99_us"] = 1e6 * quantile(best, 0.99);
  state.counters["real_time_factor"] = dt / quantile(best, 0.5);
}
BENCHMARK(BM_ManyParameters)
    ->ArgsProduct({{2, 3, 4, 6, 8}, {1, 2}, {0, 1}})
    ->Args({8, 1, 2})
    ->Args({8, 2, 2})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

// The forecast alone (the first 20 sample intervals from the prior) on 1 and
// 2 threads in the same run, for designs with Q >= 100: speedup = t1 / t2.
// Arg 0: n = 4, p = 4, Q = 2S = 140 Halton; 1: n = 8, p = 2 sparse grid (Q = 145).
void BM_ForecastThreads(benchmark::State& state) {
  const bool sparse = state.range(0) == 1;
  double t[2] = {INFINITY, INFINITY};
  int q = 0;
  for (auto _ : state) {
    for (int threads = 1; threads <= 2; ++threads) {
      const EstimatorConfig c =
          sparse ? manyParameterConfig(8, 2, PointSequence::kSmolyak, 2, threads)
                 : manyParameterConfig(4, 4, PointSequence::kHalton, 140, threads);
      const Scenario s = makeScenario(c);
      q = s.propagator->design().pointCount();
      const Eigen::MatrixXd prior = s.propagator->priorState();
      t[threads - 1] = bestOf(
          10,
          [&] {
            Eigen::MatrixXd x = prior;
            double t0 = 0.0;
            for (int k = 0; k < 20; ++k) {
              s.propagator->forecast(x, t0, s.series[k].time);
              t0 = s.series[k].time;
            }
            benchmark::DoNotOptimize(x.data());
          },
          wallSeconds);
    }
  }
  state.counters["Q"] = q;
  state.counters["one_thread_us_per_interval"] = 1e6 * t[0] / 20;
  state.counters["two_threads_us_per_interval"] = 1e6 * t[1] / 20;
  state.counters["speedup"] = t[0] / t[1];
}
BENCHMARK(BM_ForecastThreads)->Arg(0)->Arg(1)->Iterations(1)->Unit(benchmark::kMillisecond);

// Whole-set update (paper rule for one pass is the same cost; the config's
// square-root rule is used) for N samples over 3 s.
void BM_WholeSet(benchmark::State& state) {
  const int samples = static_cast<int>(state.range(0));
  const Scenario s = makeScenario(paperConfig(samples));
  const PcPropagator& prop = *s.propagator;
  const Eigen::MatrixXd theta = prop.priorState().bottomRows(prop.parameterCount());
  const NoiseModel& noise = s.config.measurement.noise;
  const std::vector<double> times = sampleTimes(s.series);
  const int repeats = samples >= 100000 ? 1 : 3;
  double simulate = INFINITY, record = INFINITY, update = INFINITY;
  for (auto _ : state) {
    for (int r = 0; r < repeats; ++r) {
      // (a) the forecast alone: Q points through every sample time.
      const Eigen::MatrixXd params = prop.parametersAtPoints(theta, nullptr);
      double c0 = threadCpuSeconds();
      const auto channels = simulateChannels(prop.model(), params, times, prop.integration());
      simulate = std::min(simulate, threadCpuSeconds() - c0);
      benchmark::DoNotOptimize(channels.data());
      // (b) forecastRecord = (a) + stacking and projection of 4N observations.
      ForecastReport report;
      c0 = threadCpuSeconds();
      const StackedObservations obs = forecastRecord(prop, theta, s.series, noise, &report);
      record = std::min(record, threadCpuSeconds() - c0);
      // (c) the Kalman update of the parameter coefficients with 4N observations.
      Eigen::MatrixXd updated = theta;
      const Eigen::VectorXd rv = obs.variances;
      c0 = threadCpuSeconds();
      const UpdateDiagnostics d = pcKalmanUpdate(updated, obs.z_coeffs, obs.z, rv, s.config.update);
      update = std::min(update, threadCpuSeconds() - c0);
      benchmark::DoNotOptimize(d.nis);
    }
  }
  state.counters["samples"] = samples;
  state.counters["observations"] = 4.0 * samples;
  state.counters["forecast_s"] = simulate;
  state.counters["stack_project_s"] = std::max(0.0, record - simulate);
  state.counters["kalman_s"] = update;
  // Everything beyond the forecast: stacking, projection and the update.
  state.counters["beyond_forecast_s"] = std::max(0.0, record - simulate) + update;
}
BENCHMARK(BM_WholeSet)
    ->Arg(100)->Arg(1000)->Arg(10000)->Arg(100000)
    ->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace pc_ekf::bench

BENCHMARK_MAIN();
