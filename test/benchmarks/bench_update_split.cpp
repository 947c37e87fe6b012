// Where a one-step update's time goes at n = 11, p = 2, Q = 160 Halton, dt =
// 0.03 s (test/benchmarks/roll_plane_tolerances.yaml, the bump record of 100
// samples): per sample, the forecast (of it: the integration of the 160
// points' models; the rest is evaluating X at the points and projecting
// back), the Kalman update, the health assessment and the statistics
// (mean, std of the parameters). The filter's own sequence, without
// re-linearisation, taken apart with the public pieces; CPU time of this
// thread on 1 and on the configured (2) forecast threads, best of 5 passes
// per piece, summed over the record.
#include "bench_support.h"
#include "pc_ekf/filter/health.h"
#include "pc_ekf/filter/kalman_update.h"
#include "pc_ekf/model/integrator.h"
#include "pc_ekf/pc/pc_statistics.h"

namespace pc_ekf::bench {
namespace {

void UpdateSplitN11(benchmark::State& state) {
  EstimatorConfig c = loadConfigFile(std::string(PC_EKF_SOURCE_DIR) +
                                     "/test/benchmarks/roll_plane_tolerances.yaml");
  c.collocation.threads = static_cast<int>(state.range(0));
  const auto model = makeModel(c, makeRoad(c));
  const auto prop = makePropagator(c, model);
  const MeasurementSeries series = synthesizeFromConfig(c, *model, 1);
  const OneStepSettings settings = makeOneStepSettings(c);
  const int ns = prop->stateCount(), np = prop->parameterCount();
  double best[5] = {INFINITY, INFINITY, INFINITY, INFINITY, INFINITY};
  for (auto _ : state) {
    for (int pass = 0; pass < 5; ++pass) {
      double sum[5] = {0, 0, 0, 0, 0};  // forecast, integration, update, health, statistics
      HealthMonitor health(*prop, settings.health);
      Eigen::MatrixXd x = prop->priorState();
      double t = 0.0;
      for (const Measurement& m : series) {
        // The integration alone, on a copy of the points' states.
        const Eigen::MatrixXd params = prop->parametersAtPoints(x.bottomRows(np), nullptr);
        Eigen::ArrayXXd y = (x.topRows(ns) * prop->design().designMatrix().transpose()).array();
        double c0 = threadCpuSeconds();
        const auto batch = model->prepare(params);
        integrate(*model, *batch, t, m.time, y, prop->integration());
        sum[1] += threadCpuSeconds() - c0;
        c0 = threadCpuSeconds();
        const ForecastReport f = prop->forecast(x, t, m.time);
        sum[0] += threadCpuSeconds() - c0;
        t = m.time;
        Eigen::MatrixXd z(static_cast<Eigen::Index>(m.channels.size()), x.cols());
        for (std::size_t i = 0; i < m.channels.size(); ++i) {
          z.row(static_cast<Eigen::Index>(i)) =
              model->observationMatrix().row(m.channels[i]) * x.topRows(ns);
        }
        c0 = threadCpuSeconds();
        const UpdateDiagnostics u =
            pcKalmanUpdate(x, z, m.values, settings.noise.variances(m), settings.rule);
        sum[2] += threadCpuSeconds() - c0;
        c0 = threadCpuSeconds();
        const Eigen::MatrixXd coefficients = x.bottomRows(np);
        const Eigen::VectorXd mean = pcMean(coefficients), sd = pcStddev(coefficients);
        sum[4] += threadCpuSeconds() - c0;
        c0 = threadCpuSeconds();
        const HealthStatus h = health.assess(u, f, coefficients);
        sum[3] += threadCpuSeconds() - c0;
        benchmark::DoNotOptimize(mean.data());
        benchmark::DoNotOptimize(sd.data());
        benchmark::DoNotOptimize(&h);
      }
      for (int i = 0; i < 5; ++i) best[i] = std::min(best[i], sum[i]);
    }
  }
  const double n = static_cast<double>(series.size());
  state.counters["forecast_us"] = 1e6 * best[0] / n;
  state.counters["integration_us"] = 1e6 * best[1] / n;
  state.counters["projection_and_rest_us"] = 1e6 * (best[0] - best[1]) / n;
  state.counters["update_us"] = 1e6 * best[2] / n;
  state.counters["health_us"] = 1e6 * best[3] / n;
  state.counters["statistics_us"] = 1e6 * best[4] / n;
  state.counters["total_us"] = 1e6 * (best[0] + best[2] + best[3] + best[4]) / n;
}
BENCHMARK(UpdateSplitN11)->Arg(1)->Arg(2)->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace pc_ekf::bench

BENCHMARK_MAIN();
