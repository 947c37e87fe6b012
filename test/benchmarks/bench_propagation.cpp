// PC vs Monte Carlo propagation (the paper's claim): mean and std of
// the four measured channels at the N = 100 sample times under the prior.
//   reference: tensor Gauss-Jacobi quadrature of the germ measure, 40 x 40
//              nodes (checked against 32 x 32: the difference is reported);
//   PC:        the Q = 30 collocation forecast exactly as the filter runs it
//              (forecast sample to sample, re-projecting at every sample);
//   MC:        plain Monte Carlo from the prior (seeded).
// Error of an estimate: for each channel, RMS over the sample times of
// (estimate - reference), divided by the RMS over the times of the reference
// std; the worst over the four channels and over {mean, std}. The MC error is
// the RMS over `replicates` independent runs of N samples; since it falls as
// N^-1/2 (checked at two N), the sample count that matches the PC's error is
// N_match = N (e_MC(N) / e_PC)^2. Wall time of MC at N_match = the measured
// time per MC sample x N_match (one thread, like the PC figure).
#include <random>

#include <yaml-cpp/yaml.h>

#include "bench_support.h"
#include "pc_ekf/reference/reference_posterior.h"
#include "pc_ekf/filter/trajectory_simulation.h"
#include "pc_ekf/pc/pc_statistics.h"

namespace pc_ekf::bench {
namespace {

struct Moments {
  Eigen::MatrixXd mean, stddev;  // 4 x N (channels x sample times)
};

// Weighted moments of the channels of parameter sets `xi` (count x n germ coordinates).
Moments simulateMoments(const Scenario& s, const Eigen::MatrixXd& xi, const Eigen::VectorXd& w,
                        int threads) {
  const ParameterMapping mapping(*s.model, s.config.uncertain);
  const Eigen::MatrixXd params = mapping.fullParameters(mapping.valuesAtGerms(xi));
  const auto channels = threads > 1 ? simulateChannelsParallel(*s.model, params, sampleTimes(s.series),
                                                               s.config.integration, threads)
                                    : simulateChannels(*s.model, params, sampleTimes(s.series),
                                                       s.config.integration);
  Moments m;
  const Eigen::Index n = static_cast<Eigen::Index>(channels.size());
  m.mean.resize(4, n);
  m.stddev.resize(4, n);
  const double wsum = w.sum();
  for (Eigen::Index k = 0; k < n; ++k) {
    const Eigen::VectorXd mean = channels[k] * w / wsum;
    const Eigen::MatrixXd centred = channels[k].colwise() - mean;
    m.mean.col(k) = mean;
    m.stddev.col(k) = (centred.array().square().matrix() * w / wsum).cwiseSqrt();
  }
  return m;
}

Moments gaussReference(const Scenario& s, int nodes_per_axis) {
  Eigen::MatrixXd nodes;
  Eigen::VectorXd weights;
  s.propagator->basis().tensorGaussRule(nodes_per_axis, &nodes, &weights);
  return simulateMoments(s, nodes, weights, 2);
}

Moments pcForecast(const Scenario& s) {
  const PcPropagator& p = *s.propagator;
  Eigen::MatrixXd x = p.priorState();
  Moments m;
  const Eigen::Index n = static_cast<Eigen::Index>(s.series.size());
  m.mean.resize(4, n);
  m.stddev.resize(4, n);
  double t = 0.0;
  for (Eigen::Index k = 0; k < n; ++k) {
    p.forecast(x, t, s.series[k].time);
    t = s.series[k].time;
    const Eigen::MatrixXd z = p.model().observationMatrix() * x.topRows(p.stateCount());
    m.mean.col(k) = pcMean(z);
    m.stddev.col(k) = pcStddev(z);
  }
  return m;
}

// Non-intrusive: the Q points simulated through the record once, the channels
// projected on the basis at each sample time.
Moments pcProjected(const Scenario& s) {
  const PcPropagator& p = *s.propagator;
  const Eigen::MatrixXd params =
      p.parametersAtPoints(p.priorState().bottomRows(p.parameterCount()), nullptr);
  const auto channels =
      simulateChannels(p.model(), params, sampleTimes(s.series), s.config.integration);
  Moments m;
  const Eigen::Index n = static_cast<Eigen::Index>(channels.size());
  m.mean.resize(4, n);
  m.stddev.resize(4, n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const Eigen::MatrixXd z = channels[k] * p.design().projector().transpose();
    m.mean.col(k) = pcMean(z);
    m.stddev.col(k) = pcStddev(z);
  }
  return m;
}

// Per channel c: (mean error, std error), each relative to the RMS reference std.
Eigen::MatrixXd channelErrors(const Moments& e, const Moments& ref) {
  Eigen::MatrixXd out(4, 2);
  for (int c = 0; c < 4; ++c) {
    const double scale = std::sqrt(ref.stddev.row(c).squaredNorm() / ref.stddev.cols());
    out(c, 0) = std::sqrt((e.mean.row(c) - ref.mean.row(c)).squaredNorm() / ref.mean.cols()) / scale;
    out(c, 1) = std::sqrt((e.stddev.row(c) - ref.stddev.row(c)).squaredNorm() / ref.stddev.cols()) / scale;
  }
  return out;
}

double momentError(const Moments& e, const Moments& ref) {
  double worst = 0.0;
  for (int c = 0; c < 4; ++c) {
    const double scale = std::sqrt(ref.stddev.row(c).squaredNorm() / ref.stddev.cols());
    const double em = std::sqrt((e.mean.row(c) - ref.mean.row(c)).squaredNorm() / ref.mean.cols());
    const double es =
        std::sqrt((e.stddev.row(c) - ref.stddev.row(c)).squaredNorm() / ref.stddev.cols());
    worst = std::max(worst, std::max(em, es) / scale);
  }
  return worst;
}

Eigen::MatrixXd priorDraws(const Scenario& s, int count, std::uint64_t seed) {
  return sampleGerms(s.propagator->basis(), count, seed);
}

// MC error (RMS over replicates) with `count` samples per replicate, and CPU seconds per sample.
std::pair<double, double> monteCarloError(const Scenario& s, const Moments& ref, int count,
                                          int replicates) {
  double sum_sq = 0.0, cpu = 0.0;
  for (int r = 0; r < replicates; ++r) {
    const Eigen::MatrixXd xi = priorDraws(s, count, 1000 + static_cast<std::uint64_t>(r));
    const double c0 = threadCpuSeconds();
    const Moments m = simulateMoments(s, xi, Eigen::VectorXd::Ones(count), 1);
    cpu += threadCpuSeconds() - c0;
    const double e = momentError(m, ref);
    sum_sq += e * e;
  }
  return {std::sqrt(sum_sq / replicates), cpu / (static_cast<double>(count) * replicates)};
}

// Reference moments and the Monte-Carlo error/cost, shared by the benchmarks below.
struct Shared {
  Scenario paper = makeScenario(paperConfig(100));
  Moments ref = gaussReference(paper, 40);
  Moments ref_coarse = gaussReference(paper, 32);
  std::pair<double, double> mc_small = monteCarloError(paper, ref, 250, 12);
  std::pair<double, double> mc_large = monteCarloError(paper, ref, 2000, 12);
};
const Shared& shared() {
  static const Shared s;
  return s;
}

void BM_PcVersusMonteCarlo(benchmark::State& state) {
  const Scenario& s = shared().paper;
  Moments pc, pc_projected;
  double pc_cpu = INFINITY, projected_cpu = INFINITY;
  const Moments& ref = shared().ref;
  const Moments& ref_coarse = shared().ref_coarse;
  const std::pair<double, double>& mc_small = shared().mc_small;
  const std::pair<double, double>& mc_large = shared().mc_large;
  const int n_small = 250, n_large = 2000;
  for (auto _ : state) {
    pc_cpu = bestOf(5, [&] { pc = pcForecast(s); });
    projected_cpu = bestOf(5, [&] { pc_projected = pcProjected(s); });
  }
  const double e_pc = momentError(pc, ref);
  const double n_match = n_large * std::pow(mc_large.first / e_pc, 2.0);
  const double q = s.propagator->design().pointCount();
  state.counters["reference_check"] = momentError(ref_coarse, ref);
  const Eigen::MatrixXd ce = channelErrors(pc, ref);
  const char* names[] = {"u1", "u2", "v1", "v2"};
  for (int c = 0; c < 4; ++c) {
    state.counters[std::string("pc_mean_error_") + names[c]] = ce(c, 0);
    state.counters[std::string("pc_std_error_") + names[c]] = ce(c, 1);
  }
  state.counters["pc_error"] = e_pc;
  const double e_proj = momentError(pc_projected, ref);
  state.counters["pc_projected_error"] = e_proj;
  state.counters["pc_projected_cpu_s"] = projected_cpu;
  const double n_match_proj = n_large * std::pow(mc_large.first / e_proj, 2.0);
  state.counters["mc_samples_to_match_projected"] = n_match_proj;
  state.counters["sample_ratio_projected"] = n_match_proj / s.propagator->design().pointCount();
  state.counters["wall_ratio_projected"] = n_match_proj * mc_large.second / projected_cpu;
  state.counters["pc_points"] = q;
  state.counters["pc_cpu_s"] = pc_cpu;
  state.counters["mc_error_250"] = mc_small.first;
  state.counters["mc_error_2000"] = mc_large.first;
  // 1 for exact N^-1/2 behaviour between the two sample counts.
  state.counters["mc_rate_check"] =
      std::log(mc_small.first / mc_large.first) / (0.5 * std::log(double(n_large) / n_small));
  state.counters["mc_cpu_per_sample_s"] = mc_large.second;
  state.counters["mc_samples_to_match"] = n_match;
  state.counters["sample_ratio"] = n_match / q;
  state.counters["mc_cpu_at_match_s"] = n_match * mc_large.second;
  state.counters["wall_ratio"] = n_match * mc_large.second / pc_cpu;
}
BENCHMARK(BM_PcVersusMonteCarlo)->Iterations(1)->Unit(benchmark::kSecond);

// The same comparison for other designs: higher PC orders p with Q = 2S
// Halton points (least squares), and tensor Gauss-Jacobi rules of p + 1
// nodes per germ (quadrature projection). Args: p, Gauss nodes per germ (0:
// Halton). The Halton least-squares error does not fall with p (aliasing of
// the higher modes into the fitted ones); the Gauss projection's falls fast
// while MC needs N ~ 1 / error^2.
void BM_PcOrderVersusMonteCarlo(benchmark::State& state) {
  const int order = static_cast<int>(state.range(0));
  EstimatorConfig c = paperConfig(100);
  c.pc_order = order;
  c.collocation.points = (order + 1) * (order + 2);  // 2S for n = 2
  if (state.range(1) > 0) {  // tensor Gauss rule with range(1) nodes per germ
    c.collocation.sequence = PointSequence::kGauss;
    c.collocation.points = static_cast<int>(state.range(1));
  }
  const Scenario s = makeScenario(c);
  const Moments& ref = shared().ref;
  const std::pair<double, double>& mc = shared().mc_large;
  Moments pc, projected;
  double pc_cpu = INFINITY, projected_cpu = INFINITY;
  for (auto _ : state) {
    pc_cpu = bestOf(3, [&] { pc = pcForecast(s); });
    projected_cpu = bestOf(3, [&] { projected = pcProjected(s); });
  }
  const double q = s.propagator->design().pointCount();
  const double e_pc = momentError(pc, ref), e_proj = momentError(projected, ref);
  const double n_pc = 2000.0 * std::pow(mc.first / e_pc, 2.0);
  const double n_proj = 2000.0 * std::pow(mc.first / e_proj, 2.0);
  state.counters["p"] = order;
  state.counters["Q"] = q;
  state.counters["pc_error"] = e_pc;
  state.counters["sample_ratio"] = n_pc / q;
  state.counters["wall_ratio"] = n_pc * mc.second / pc_cpu;
  state.counters["pc_projected_error"] = e_proj;
  state.counters["sample_ratio_projected"] = n_proj / q;
  state.counters["wall_ratio_projected"] = n_proj * mc.second / projected_cpu;
}
BENCHMARK(BM_PcOrderVersusMonteCarlo)
    ->Args({6, 0})->Args({8, 0})->Args({4, 5})->Args({6, 7})->Args({8, 9})->Args({12, 13})
    ->Iterations(1)->Unit(benchmark::kSecond);

// ---- accuracy against cost per design (the paper case, n = 2) ----
// Moment error as above (filter-style forecast against the 40 x 40 Gauss
// reference) and the one-step filter's final estimate (square root, the
// paper's N = 100 record, seed 1) against the exact posterior of that record:
// filter_mean_error = max over parameters |mean - mean_ref| / std_ref,
// filter_std_error = max |std / std_ref - 1|; relinearized_*: the same with
// re-linearisation (shrink 0.01, width 20: what is the design's, what the
// first updates' linearisation).
const ReferencePosterior& exactPosterior() {
  static const ReferencePosterior p = [] {
    const Scenario& s = shared().paper;
    ReferencePosteriorSettings ps = makeReferenceSettings(s.config);
    ps.threads = 2;
    return computeReferencePosterior(*s.model, ParameterMapping(*s.model, s.config.uncertain),
                                     s.series, s.config.measurement.noise, s.config.integration, ps);
  }();
  return p;
}

void designCounters(benchmark::State& state, EstimatorConfig c) {
  c.collocation.threads = 1;
  c.update = UpdateRule::kSquareRoot;
  const Scenario s = makeScenario(c);
  const std::pair<double, double>& mc = shared().mc_large;
  Moments pc;
  double pc_cpu = INFINITY;
  StepResult plain, relin;
  const auto run = [&](const RelinearizeSettings& rl) {
    OneStepSettings settings = makeOneStepSettings(s.config);
    settings.relinearize = rl;
    OneStepFilter filter(s.propagator, settings);
    StepResult r;
    for (const Measurement& m : shared().paper.series) r = filter.process(m);
    return r;
  };
  for (auto _ : state) {
    pc_cpu = bestOf(3, [&] { pc = pcForecast(s); });
    plain = run(RelinearizeSettings{});
    relin = run(RelinearizeSettings{0.01, 20.0, 4, 1000});  // performance.md's bracketed figures
  }
  const ReferencePosterior& ref = exactPosterior();
  const double q = s.propagator->design().pointCount();
  const double e_pc = momentError(pc, shared().ref);
  const double n_match = 2000.0 * std::pow(mc.first / e_pc, 2.0);
  state.counters["sequence"] = static_cast<double>(c.collocation.sequence);
  state.counters["regression"] =
      s.propagator->design().projection() == ProjectionMethod::kRegression;
  state.counters["p"] = c.pc_order;
  state.counters["S"] = s.propagator->termCount();
  state.counters["Q"] = q;
  state.counters["pc_error"] = e_pc;
  state.counters["sample_ratio"] = n_match / q;
  state.counters["pc_cpu_s"] = pc_cpu;
  state.counters["wall_ratio"] = n_match * mc.second / pc_cpu;
  for (const auto& [prefix, r] : {std::pair<std::string, const StepResult&>{"filter", plain},
                                  {"relinearized", relin}}) {
    state.counters[prefix + "_mean_error"] =
        ((r.mean - ref.mean).array().abs() / ref.stddev.array()).maxCoeff();
    state.counters[prefix + "_std_error"] =
        ((r.stddev.array() / ref.stddev.array()) - 1.0).abs().maxCoeff();
  }
}

struct Design {
  PointSequence sequence;
  int count;  // Q, nodes per germ (gauss) or level (smolyak)
  int order;
  ProjectionMethod projection;
};
const std::vector<Design>& curveDesigns() {
  static const std::vector<Design> d = {
      {PointSequence::kHalton, 30, 4, ProjectionMethod::kRegression},  // the paper's
      {PointSequence::kHalton, 60, 4, ProjectionMethod::kRegression},
      {PointSequence::kHammersley, 30, 4, ProjectionMethod::kRegression},
      {PointSequence::kGauss, 4, 3, ProjectionMethod::kQuadrature},
      {PointSequence::kGauss, 5, 4, ProjectionMethod::kQuadrature},
      {PointSequence::kGauss, 6, 5, ProjectionMethod::kQuadrature},
      {PointSequence::kSmolyak, 3, 3, ProjectionMethod::kQuadrature},
      {PointSequence::kSmolyak, 4, 4, ProjectionMethod::kQuadrature},
      {PointSequence::kSmolyak, 4, 4, ProjectionMethod::kRegression},
      {PointSequence::kSmolyak, 5, 5, ProjectionMethod::kQuadrature},
  };
  return d;
}

void BM_DesignCurve(benchmark::State& state) {
  const Design& d = curveDesigns()[static_cast<std::size_t>(state.range(0))];
  EstimatorConfig c = paperConfig(100);
  c.pc_order = d.order;
  c.collocation.sequence = d.sequence;
  c.collocation.points = d.count;
  c.collocation.level = d.count;
  c.collocation.projection = d.projection;
  designCounters(state, c);
}
BENCHMARK(BM_DesignCurve)->DenseRange(0, 9)->Iterations(1)->Unit(benchmark::kSecond);

// The design a user gets for the paper case without choosing one:
// config/speed_bump.yaml without its pc: and collocation: sections, so the
// parser's defaults (order, truncation, sequence `auto`, points).
void BM_DesignDefault(benchmark::State& state) {
  YAML::Node node = YAML::LoadFile(configPath());
  node.remove("pc");
  node.remove("collocation");
  const EstimatorConfig given = parseConfig(node, "speed_bump.yaml without pc: and collocation:");
  EstimatorConfig c = paperConfig(100);
  c.pc_order = given.pc_order;
  c.pc_truncation = given.pc_truncation;
  c.batch_tolerance_interactions = given.batch_tolerance_interactions;
  c.collocation = given.collocation;
  designCounters(state, c);
}
BENCHMARK(BM_DesignDefault)->Iterations(1)->Unit(benchmark::kSecond);

// ---- many parameters: sparse grid against Q = 2S Halton at the same n and p ----
// Reference: an anisotropic tensor Gauss rule, 10 nodes for M and d_CG (their
// +-50 % / +-25 % ranges) and 3 for each +-10 % parameter (degree 5), checked
// against 8 and 3 nodes (reference_check).
Moments anisotropicReference(const Scenario& s, int wide_nodes) {
  const PolynomialBasis& basis = s.propagator->basis();
  const int n = basis.dimension();
  std::vector<QuadratureRule> rules;
  Eigen::Index total = 1;
  for (int d = 0; d < n; ++d) {
    rules.push_back(basis.family(d).gaussRule(d < 2 ? wide_nodes : 3));
    total *= rules.back().nodes.size();
  }
  Eigen::MatrixXd nodes(total, n);
  Eigen::VectorXd weights(total);
  for (Eigen::Index r = 0; r < total; ++r) {
    Eigen::Index rest = r;
    double w = 1.0;
    for (int d = n - 1; d >= 0; --d) {
      const Eigen::Index m = rules[d].nodes.size(), i = rest % m;
      rest /= m;
      nodes(r, d) = rules[d].nodes(i);
      w *= rules[d].weights(i);
    }
    weights(r) = w;
  }
  return simulateMoments(s, nodes, weights, 2);
}

void BM_ManyParametersAccuracy(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0)), p = scalingOrder(n);
  const Scenario sparse = makeScenario(manyParameterConfig(n, p, PointSequence::kSmolyak, p));
  const Scenario halton =
      makeScenario(manyParameterConfig(n, p, PointSequence::kHalton, 2 * basisTerms(n, p)));
  Moments ref, ref_check, m_sparse, m_halton;
  for (auto _ : state) {
    ref = anisotropicReference(sparse, 10);
    ref_check = anisotropicReference(sparse, 8);
    m_sparse = pcForecast(sparse);
    m_halton = pcForecast(halton);
  }
  state.counters["n"] = n;
  state.counters["p"] = p;
  state.counters["Q_smolyak"] = sparse.propagator->design().pointCount();
  state.counters["Q_halton"] = halton.propagator->design().pointCount();
  state.counters["reference_check"] = momentError(ref_check, ref);
  state.counters["smolyak_error"] = momentError(m_sparse, ref);
  state.counters["halton_error"] = momentError(m_halton, ref);
  if (n == 8) {  // the hyperbolic-cross row: p = 4, q = 0.5, Q = 2S Halton
    const Scenario hyperbolic = makeScenario(hyperbolicConfig(n));
    state.counters["Q_hyperbolic"] = hyperbolic.propagator->design().pointCount();
    state.counters["hyperbolic_error"] = momentError(pcForecast(hyperbolic), ref);
  }
}
BENCHMARK(BM_ManyParametersAccuracy)
    ->Arg(3)
    ->Arg(4)
    ->Arg(6)
    ->Arg(8)
    ->Iterations(1)
    ->Unit(benchmark::kSecond);

}  // namespace
}  // namespace pc_ekf::bench

BENCHMARK_MAIN();
