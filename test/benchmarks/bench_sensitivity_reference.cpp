// The sensitivity's reference (docs/studies/real_vehicle_reference.md §4): total
// Sobol indices by the Jansen estimator on plain Monte Carlo runs of the
// model, against estimate_offline --sensitivity's (simulated_sensitivity.h),
// on vehicle_live.yaml over the paper bump, N = 100. Prints per parameter and
// channel both, the Jansen estimate's 95 % half-width, the largest difference
// over the indices >= 0.05 and whether the top 3 per channel agree; then, per
// parameter, the largest index of each and of the filters' re-projected
// forecast (prior_sensitivity.h), the comparison of docs/studies/real_vehicle_reference.md §4. Not part
// of bench.sh (seconds to a minute).
//   PC_EKF_JANSEN_SAMPLES (20000 per matrix: (n + 2) x that many runs),
//   PC_EKF_JANSEN_SEED (7), PC_EKF_JANSEN_CONFIG (vehicle_live.yaml; its road
//   is replaced by the speed bump when it comes from the topic)
#include <cstdio>
#include <cstdlib>
#include <numeric>
#include <random>

#include "bench_support.h"
#include "pc_ekf/sensitivity/simulated_sensitivity.h"
#include "pc_ekf/io/record_sensitivity.h"

namespace pc_ekf::bench {
namespace {

std::vector<int> topThree(const Eigen::VectorXd& v) {
  std::vector<int> order(v.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return v[a] > v[b]; });
  order.resize(3);
  return order;
}

void BM_SensitivityAgainstJansen(benchmark::State& state) {
  const char* path = std::getenv("PC_EKF_JANSEN_CONFIG");
  EstimatorConfig c = loadConfigFile(path ? path : configPath("vehicle_live.yaml"));
  if (c.road.source == RoadSource::kTopic) {
    c.road.source = RoadSource::kSpeedBump;
    c.sampling.samples = 100;
  }
  const int draws = std::getenv("PC_EKF_JANSEN_SAMPLES") ? std::atoi(std::getenv("PC_EKF_JANSEN_SAMPLES")) : 20000;
  const auto model = makeModel(c, makeRoad(c));
  const ParameterMapping mapping(*model, c.uncertain);
  const std::vector<double> times = uniformSampleTimes(c.sampling.samples, c.sampling.duration);
  const std::vector<int> channels = channelIndices(c);
  const int n = mapping.count(), nc = static_cast<int>(channels.size());
  const Eigen::Index t = static_cast<Eigen::Index>(times.size());
  PriorSensitivity product, forecast;
  Eigen::MatrixXd jansen(n, nc), half(n, nc);
  for (auto _ : state) {
    product = recordSensitivity(c, model, times);
    // For comparison: the filters' forecast, re-projected at every sample, on
    // the batch methods' design (what --sensitivity read before whole-record runs).
    forecast = priorSensitivity(*makePropagator(batchDesignConfig(c), model), times, channels);
    std::mt19937_64 rng(std::getenv("PC_EKF_JANSEN_SEED") ? std::atoll(std::getenv("PC_EKF_JANSEN_SEED")) : 7);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    std::vector<OrthonormalFamily> family;
    for (const GermSpec& g : mapping.germs()) family.emplace_back(g);
    Eigen::MatrixXd a(n, draws), b(n, draws);
    for (int j = 0; j < draws; ++j) {
      for (int i = 0; i < n; ++i) {
        a(i, j) = family[i].inverseCdf(uniform(rng));
        b(i, j) = family[i].inverseCdf(uniform(rng));
      }
    }
    const Eigen::MatrixXd fa = recordReadings(*model, mapping, a, times, channels, c.integration, 0);
    const Eigen::MatrixXd fb = recordReadings(*model, mapping, b, times, channels, c.integration, 0);
    Eigen::VectorXd variance = Eigen::VectorXd::Zero(nc);
    for (Eigen::Index o = 0; o < fa.rows(); ++o) {
      Eigen::VectorXd both(2 * draws);
      both << fa.row(o).transpose(), fb.row(o).transpose();
      variance[o / t] += (both.array() - both.mean()).square().sum() / (2.0 * draws - 1.0);
    }
    for (int i = 0; i < n; ++i) {
      Eigen::MatrixXd ab = a;
      ab.row(i) = b.row(i);
      const Eigen::MatrixXd fab = recordReadings(*model, mapping, ab, times, channels, c.integration, 0);
      for (int ch = 0; ch < nc; ++ch) {
        // Jansen: T_i = E[(f(A) - f(A_B^i))^2] / 2 / V, summed over the samples.
        const Eigen::ArrayXd per = (fa.middleRows(ch * t, t) - fab.middleRows(ch * t, t))
                                       .array().square().colwise().sum().transpose() / 2.0;
        const double mean = per.mean();
        const double se = std::sqrt((per - mean).square().sum() / (draws - 1.0) / draws);
        jansen(i, ch) = mean / variance[ch];
        half(i, ch) = 1.96 * se / variance[ch];
      }
    }
  }
  std::printf("%-24s", "parameter");
  for (const auto& name : product.channels) std::printf(" %21s", (name + " product / Jansen").c_str());
  std::printf("\n");
  double worst = 0.0;
  for (int i = 0; i < n; ++i) {
    std::printf("%-24s", product.parameters[i].c_str());
    for (int ch = 0; ch < nc; ++ch) {
      std::printf("  %.4f / %.4f+-%.4f", product.total(i, ch), jansen(i, ch), half(i, ch));
      if (product.total(i, ch) >= 0.05 || jansen(i, ch) >= 0.05) {
        worst = std::max(worst, std::abs(product.total(i, ch) - jansen(i, ch)));
      }
    }
    std::printf("\n");
  }
  int same = 0;
  for (int ch = 0; ch < nc; ++ch) {
    same += topThree(product.total.col(ch)) == topThree(jansen.col(ch));
  }
  std::printf("largest over the channels: product / Jansen / the filters' forecast\n");
  for (int i = 0; i < n; ++i) {
    std::printf("  %-24s %.4f / %.4f / %.4f\n", product.parameters[i].c_str(), product.largestTotal(i),
                jansen.row(i).maxCoeff(), forecast.largestTotal(i));
  }
  if (forecast.unexplained.size() > 0) {
    std::printf("missed by the forecast's one-step leave-one-out error:");
    for (Eigen::Index ch = 0; ch < forecast.unexplained.size(); ++ch) {
      std::printf(" %.4f", forecast.unexplained[ch]);
    }
    std::printf("\n");
  }
  std::printf("expansion: %s\nlargest |product - Jansen| over the indices >= 0.05: %.4f; top 3 the same on %d of %d channels\n",
              product.expansion.c_str(), worst, same, nc);
  state.counters["largest_difference"] = worst;
  state.counters["top3_same_channels"] = same;
  state.counters["jansen_runs"] = static_cast<double>(draws) * (n + 2);
}
BENCHMARK(BM_SensitivityAgainstJansen)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

}  // namespace
}  // namespace pc_ekf::bench

BENCHMARK_MAIN();
