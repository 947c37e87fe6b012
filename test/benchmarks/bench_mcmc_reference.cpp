// The 11-parameter reference of docs/studies/real_vehicle_reference.md: one speed-bump
// record (test/benchmarks/tolerances_n11.yaml: M, d_CG and nine tolerances,
// data from a vehicle off by a few percent), estimated by one-step (square
// root) and ES-MDA, and sampled by the long-chain MCMC reference
// (mcmc_reference.h) on the same exact likelihood. Prints, per parameter, the
// reference mean +- std (R-hat, ESS) and each filter's mean error and std
// ratio in reference std units. Not part of bench.sh (minutes of wall time).
//   PC_EKF_MCMC_CHAINS (16), PC_EKF_MCMC_BURN_IN (4000), PC_EKF_MCMC_SAMPLES (20000),
//   PC_EKF_MCMC_SEED (1), PC_EKF_MCMC_CONFIG (that file; road.source none too),
//   PC_EKF_MCMC_SAMPLER (metropolis; ensemble: CHAINS are then the walkers; hamiltonian;
//   conditional_laplace: CHAINS are batches of SAMPLES independent draws, BURN_IN unused,
//   PC_EKF_MCMC_RIDGE (2) ridge dimensions, PC_EKF_MCMC_GRID (21) nodes per ridge axis),
//   PC_EKF_MCMC_THIN (1), PC_EKF_MCMC_CHAIN_MEANS (set: each chain's level in M)
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "bench_support.h"
#include "pc_ekf/reference/mcmc_reference.h"
#include "pc_ekf/io/offline_estimation.h"
#include "pc_ekf/io/road_free_stream.h"

namespace pc_ekf::bench {
namespace {

long envInt(const char* name, long fallback) {
  const char* v = std::getenv(name);
  return v ? std::atol(v) : fallback;
}

Scenario roadFreeScenario(const EstimatorConfig& c) {
  const RoadFreeRecord split =
      roadFreeRecord(c, synthesizeFromConfig(c, *truthOnItsRoad(c), c.truth.seed),
                     c.sampling.interval());
  Scenario s;
  s.config = c;
  s.model = split.model;
  s.series = split.outputs;
  return s;
}

void BM_McmcReferenceN11(benchmark::State& state) {
  const char* path = std::getenv("PC_EKF_MCMC_CONFIG");
  const EstimatorConfig c = loadConfigFile(
      path ? path : std::string(PC_EKF_SOURCE_DIR) + "/test/benchmarks/tolerances_n11.yaml");
  // road.source none: the truth drives its own road, and the estimator's
  // model is built from the record (its outputs carry the inherited variances).
  const Scenario s = c.road.source == RoadSource::kNone ? roadFreeScenario(c) : makeScenario(c, c.truth.seed);
  const ParameterMapping mapping(*s.model, c.uncertain);
  const OfflineResult one_step =
      runOfflineEstimation(c, s.series, s.model, EstimationMethod::kOneStep, c.truth.seed);
  const OfflineResult es_mda =
      runOfflineEstimation(c, s.series, s.model, EstimationMethod::kEsMda, c.truth.seed);
  McmcSettings ms;
  ms.chains = static_cast<int>(envInt("PC_EKF_MCMC_CHAINS", 16));
  ms.burn_in = static_cast<int>(envInt("PC_EKF_MCMC_BURN_IN", 4000));
  ms.samples = static_cast<int>(envInt("PC_EKF_MCMC_SAMPLES", 20000));
  ms.seed = static_cast<std::uint64_t>(envInt("PC_EKF_MCMC_SEED", 1));
  ms.thin = static_cast<int>(envInt("PC_EKF_MCMC_THIN", 1));
  const char* sampler = std::getenv("PC_EKF_MCMC_SAMPLER");
  const std::string sampler_name = sampler ? sampler : "metropolis";
  if (sampler_name == "ensemble") {
    ms.sampler = McmcSampler::kEnsemble;
  } else if (sampler_name == "hamiltonian") {
    ms.sampler = McmcSampler::kHamiltonian;
  } else if (sampler_name == "conditional_laplace") {
    ms.sampler = McmcSampler::kConditionalLaplace;
    ms.ridge_dimensions = static_cast<int>(envInt("PC_EKF_MCMC_RIDGE", ms.ridge_dimensions));
    ms.grid_points = static_cast<int>(envInt("PC_EKF_MCMC_GRID", ms.grid_points));
  } else if (sampler_name != "metropolis") {
    throw std::invalid_argument(
        "PC_EKF_MCMC_SAMPLER: metropolis, ensemble, hamiltonian or conditional_laplace, not " +
        sampler_name);
  }
  // Mode search from the prior mean and both filters' estimates.
  std::vector<Eigen::VectorXd> starts{Eigen::VectorXd::Zero(mapping.count())};
  for (const OfflineResult* r : {&one_step, &es_mda}) {
    Eigen::VectorXd xi(mapping.count());
    for (int i = 0; i < mapping.count(); ++i) xi[i] = r->parameters[i].xi_mean;
    starts.push_back(xi);
  }
  McmcReference ref;
  for (auto _ : state) {
    ref =
        runMcmcReference(*s.model, mapping, s.series, c.measurement.noise, c.integration, 2, starts,
                         ms, [](const std::string& m) { std::fprintf(stderr, "%s\n", m.c_str()); });
  }
  std::printf(
      "MCMC (%s): %d chains x (%d burn-in + %d kept, thin %d), acceptance %.3f, scale %.2f, %ld "
      "simulations, %.1f s; %d competing modes; one-step %.2f s healthy %d, ES-MDA %.2f s "
      "healthy %d\n",
      sampler_name.c_str(), ms.chains, ms.burn_in, ms.samples, ms.thin, ref.acceptance, ref.proposal_scale, ref.simulations,
      ref.seconds, ref.competing_modes, one_step.wall_seconds, one_step.healthy,
      es_mda.wall_seconds, es_mda.healthy);
  if (ms.sampler == McmcSampler::kConditionalLaplace) {
    std::printf("importance sampling: %d ridge nodes, Kish ESS %.0f of %d draws, largest weight %.2e\n",
                ref.ridge_nodes, ref.importance_ess, ms.chains * ms.samples, ref.largest_weight);
  }
  // How far the Laplace covariance H^-1 at the mode is from the draws': the
  // eigenvalues of the draws' covariance whitened by H^-1 (all 1 for a Gaussian).
  {
    const Eigen::VectorXd ev = Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd>(
                                   ref.xi_covariance, ref.laplace_xi_covariance)
                                   .eigenvalues();
    std::printf("draws' covariance / Laplace: eigenvalues %.3g ... %.3g\n", ev.minCoeff(),
                ev.maxCoeff());
  }
  // Where each chain sits in M (germ units): its mean, std and first / last
  // kept draw. Chains apart by more than their own spread are stuck, not mixing.
  for (std::size_t c = 0; c < ref.draws.size() && std::getenv("PC_EKF_MCMC_CHAIN_MEANS"); ++c) {
    const Eigen::VectorXd m0 = ref.draws[c].row(0).transpose();
    std::printf("chain %2zu: M germ mean %.4f std %.4f first %.4f last %.4f\n", c, m0.mean(),
                std::sqrt((m0.array() - m0.mean()).square().mean()), m0[0], m0[m0.size() - 1]);
  }
  std::printf("%-22s %14s %12s %7s %7s %8s | %9s %8s | %9s %8s | %9s | %8s\n", "parameter", "ref mean",
              "ref std", "R-hat", "ESS", "lapl/ref", "1step dz", "std/ref", "ESMDA dz", "std/ref",
              "truth dz", "mode dz");
  // The posterior mode (the Laplace step's) in the same units: a mode far from
  // the mean is a skewed posterior, which a Gaussian update cannot follow.
  const Eigen::VectorXd mode = mapping.valuesAtGerms(ref.mode_xi.transpose()).col(0);
  // The truth of every parameter (load: truth.xi; tolerances: truth.vehicle).
  const Eigen::VectorXd truth_full = truthParameters(c, *s.model);
  const auto& all = s.model->parameterNames();
  double worst = 0.0;
  for (int i = 0; i < mapping.count(); ++i) {
    const double m = ref.mean[i], sd = ref.stddev[i];
    const ParameterSummary &a = one_step.parameters[i], &b = es_mda.parameters[i];
    const double t = truth_full[std::find(all.begin(), all.end(), ref.names[i]) - all.begin()];
    std::printf("%-22s %14.6g %12.4g %7.4f %7.0f %8.3f | %9.3f %8.3f | %9.3f %8.3f | %9.3f | %8.3f\n",
                ref.names[i].c_str(), m, sd, ref.r_hat[i], ref.effective_size[i],
                ref.laplace_xi_stddev[i] / ref.xi_stddev[i], (a.mean - m) / sd,
                a.stddev / sd, (b.mean - m) / sd, b.stddev / sd, (t - m) / sd, (mode[i] - m) / sd);
    worst = std::max(worst, ref.r_hat[i]);
  }
  state.counters["max_r_hat"] = worst;
  state.counters["min_ess"] = ref.effective_size.minCoeff();
  state.counters["simulations"] = static_cast<double>(ref.simulations);
  state.counters["mcmc_s"] = ref.seconds;
}
BENCHMARK(BM_McmcReferenceN11)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

}  // namespace
}  // namespace pc_ekf::bench

BENCHMARK_MAIN();
