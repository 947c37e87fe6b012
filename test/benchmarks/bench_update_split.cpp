// Where a one-step update's time goes, per sample: the forecast (of it: the
// integration of the points' models; the rest is evaluating X at the points
// and projecting back), the Kalman update, the health assessment (as the
// node runs it: the mass outside the support at every sample) and the
// statistics (mean, std of the parameters). The filter's own sequence,
// without re-linearisation, taken apart with the public pieces; CPU time of
// this thread on 1 and on 2 forecast threads, best of 5 passes per piece,
// summed over the record.
//   UpdateSplitN11: n = 11, p = 2, Q = 160 Halton, dt = 0.03 s
//     (test/benchmarks/roll_plane_tolerances.yaml, the bump record of 100 samples).
//   UpdateSplitLive/<config>/<threads>: config 0 = config/vehicle_live.yaml,
//     1 = config/full_car_live.yaml, as shipped but the road: the speed bump,
//     N = 100 over 3 s.
//   RunSplitLive/<config>: the same records, per run (wall time, best of 3):
//     the filter as configured (re-linearisation re-runs, deferred or not,
//     its forecast threads), the same without re-linearisation (the
//     difference is the re-runs' cost), the PDF draws (set-up) and the final
//     histograms, estimate_offline's whole estimation (runOfflineEstimation:
//     filter, coherence twin, PDFs, summaries) and what writing its output
//     files (samples.csv row by row during the run) adds to it.
#include <filesystem>

#include "bench_support.h"
#include "pc_ekf/filter/health.h"
#include "pc_ekf/filter/kalman_update.h"
#include "pc_ekf/io/offline_estimation.h"
#include "pc_ekf/model/integrator.h"
#include "pc_ekf/pc/pc_statistics.h"
#include "pc_ekf/pc/pdf_sampler.h"

namespace pc_ekf::bench {
namespace {

// A shipped live config as shipped but on the speed bump, N = 100 over 3 s.
EstimatorConfig liveOnBump(int which) {
  EstimatorConfig c =
      loadConfigFile(std::string(PC_EKF_SOURCE_DIR) +
                     (which == 0 ? "/config/vehicle_live.yaml" : "/config/full_car_live.yaml"));
  c.road.source = RoadSource::kSpeedBump;
  c.sampling.samples = 100;
  c.sampling.duration = 3.0;
  return c;
}

void splitPerSample(benchmark::State& state, const EstimatorConfig& c) {
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
  state.counters["S"] = prop->termCount();
  state.counters["Q"] = prop->design().pointCount();
}

void UpdateSplitN11(benchmark::State& state) {
  EstimatorConfig c = loadConfigFile(std::string(PC_EKF_SOURCE_DIR) +
                                     "/test/benchmarks/roll_plane_tolerances.yaml");
  c.collocation.threads = static_cast<int>(state.range(0));
  splitPerSample(state, c);
}
BENCHMARK(UpdateSplitN11)->Arg(1)->Arg(2)->Iterations(1)->Unit(benchmark::kMillisecond);

void UpdateSplitLive(benchmark::State& state) {
  EstimatorConfig c = liveOnBump(static_cast<int>(state.range(0)));
  c.collocation.threads = static_cast<int>(state.range(1));
  splitPerSample(state, c);
}
BENCHMARK(UpdateSplitLive)
    ->Args({0, 1})
    ->Args({0, 2})
    ->Args({1, 1})
    ->Args({1, 2})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

void RunSplitLive(benchmark::State& state) {
  const EstimatorConfig c = liveOnBump(static_cast<int>(state.range(0)));
  const auto model = makeModel(c, makeRoad(c));
  const auto prop = makePropagator(c, model);
  const MeasurementSeries series = synthesizeFromConfig(c, *model, c.truth.seed);
  const auto filterWall = [&](bool relinearize) {
    OneStepSettings settings = makeOneStepSettings(c);
    if (!relinearize) settings.relinearize.max_restarts = 0;
    StepResult last;
    const double s = bestOf(
        3,
        [&] {
          OneStepFilter filter(prop, settings);
          for (const Measurement& m : series) last = filter.process(m);
        },
        wallSeconds);
    return std::make_pair(s, last);
  };
  const std::string dir =
      (std::filesystem::temp_directory_path() / "pc_ekf_run_split_live").string();
  double filter_s = 0, plain_s = 0, setup_s = 0, hist_s = 0, estimate_s = 0, output_s = 0;
  for (auto _ : state) {
    const auto [with, last] = filterWall(true);
    filter_s = with;
    plain_s = filterWall(false).first;
    std::shared_ptr<const ParameterPdfSampler> pdfs;
    setup_s = bestOf(
        3, [&] { pdfs = makePdfSampler(c, prop->basis(), prop->parameterCount()); }, wallSeconds);
    hist_s = bestOf(
        3, [&] { benchmark::DoNotOptimize(pdfs->histograms(last.coefficients)); }, wallSeconds);
    OfflineResult r;
    estimate_s = bestOf(
        3,
        [&] {
          r = runOfflineEstimation(c, series, model, EstimationMethod::kOneStep, c.truth.seed);
        },
        wallSeconds);
    // The rows are written while the run goes on: the outputs' cost is
    // what a run with them takes beyond one without.
    output_s = bestOf(
                   3,
                   [&] {
                     OfflineOutputs out(dir);
                     out.finish(runOfflineEstimation(c, series, model, EstimationMethod::kOneStep,
                                                     c.truth.seed, {}, nullptr, &out));
                   },
                   wallSeconds) -
               estimate_s;
  }
  std::filesystem::remove_all(dir);
  state.counters["S"] = prop->termCount();
  state.counters["Q"] = prop->design().pointCount();
  state.counters["filter_ms"] = 1e3 * filter_s;
  state.counters["filter_without_relinearization_ms"] = 1e3 * plain_s;
  state.counters["relinearization_ms"] = 1e3 * (filter_s - plain_s);
  state.counters["pdf_setup_ms"] = 1e3 * setup_s;
  state.counters["pdf_histograms_ms"] = 1e3 * hist_s;
  state.counters["estimation_ms"] = 1e3 * estimate_s;
  state.counters["output_ms"] = 1e3 * output_s;
}
BENCHMARK(RunSplitLive)->Arg(0)->Arg(1)->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace pc_ekf::bench

BENCHMARK_MAIN();
