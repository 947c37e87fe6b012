// Parameter PDFs at n = 11 (test/benchmarks/roll_plane_tolerances.yaml: the
// roll plane with the nine vehicle values' tolerances, p = 2, S = 78), 10^5
// draws, 60 bins: the histograms of every parameter from one sampler
// (PdfN11, per call: what the node pays per parameter_pdf message), and the
// sampler's construction (PdfN11Setup: germ draws and their univariate
// polynomial values, once per design). Wall time, one thread; pdf_n11_ms in
// bench.json is PdfN11 (docs/realtime.md).
#include <random>

#include "bench_support.h"
#include "pc_ekf/pc/pdf_sampler.h"

namespace pc_ekf::bench {
namespace {

PolynomialBasis n11Basis() {
  const EstimatorConfig c = loadConfigFile(std::string(PC_EKF_SOURCE_DIR) +
                                           "/test/benchmarks/roll_plane_tolerances.yaml");
  return makePropagator(c, makeModel(c, makeRoad(c)))->basis();
}

Eigen::MatrixXd spreadCoefficients(int parameters, int terms) {
  std::mt19937 rng(1);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd c(parameters, terms);
  for (int i = 0; i < parameters; ++i) {
    c(i, 0) = 1.0 + i;
    for (int j = 1; j < terms; ++j) c(i, j) = 0.01 * normal(rng) / j;
  }
  return c;
}

void PdfN11(benchmark::State& state) {
  const PolynomialBasis basis = n11Basis();
  const ParameterPdfSampler sampler(basis, 100000, 60, 11);
  const Eigen::MatrixXd c = spreadCoefficients(basis.dimension(), basis.size());
  for (auto _ : state) {
    const std::vector<Histogram> h = sampler.histograms(c);
    benchmark::DoNotOptimize(h.data());
  }
  state.counters["parameters"] = basis.dimension();
  state.counters["terms"] = basis.size();
}
BENCHMARK(PdfN11)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Repetitions(5)
    ->ReportAggregatesOnly(false);

void PdfN11Setup(benchmark::State& state) {
  const PolynomialBasis basis = n11Basis();
  for (auto _ : state) {
    const ParameterPdfSampler sampler(basis, 100000, 60, 11);
    benchmark::DoNotOptimize(&sampler);
  }
}
BENCHMARK(PdfN11Setup)->Unit(benchmark::kMillisecond)->UseRealTime()->Repetitions(3);

}  // namespace
}  // namespace pc_ekf::bench

BENCHMARK_MAIN();
