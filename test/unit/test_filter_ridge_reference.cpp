// One-step and ES-MDA against the converged reference posterior on a small
// ridge: the speed bump (N = 100, 1 % noise, no sensor floor) with the load M,
// its position and four vehicle values known to a tolerance, the body mass
// (3 %) among them. The readings are deviations from rest, so a heavier load
// on a lighter body reads the same (M trades against the body mass), and
// only the body mass's tolerance bounds M's spread. The reference: the
// conditional-Laplace sampler (mcmc_reference.h) on the same likelihood.
// Shipped settings (vehicle_live.yaml's re-linearisation with the prior put
// back; ES-MDA's restarts) against the filters without them.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "pc_ekf/reference/mcmc_reference.h"
#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/io/offline_estimation.h"

namespace pc_ekf {
namespace {

const char* kRidge =
    "uncertain:\n"
    "  - {name: added_mass, nominal: 200.0, relative_range: 0.5}\n"
    "  - {name: added_mass_position, nominal: 0.762, relative_range: 0.25}\n"
    "tolerances: {bar_mass: 0.03, spring_linear_left: 0.10, spring_linear_right: 0.10,\n"
    "             bar_inertia: 0.15}\n"
    "pc: {order: 2}\n"
    "collocation: {sequence: halton, points: 56}\n"
    "road: {source: speed_bump}\n"
    "sampling: {samples: 100, duration: 3.0}\n"
    "integration: {method: dp5, max_step: 0.005}\n"
    "measurement: {r_rule: paper, r_relative: 0.01, noise_relative: 0.01, noise_floor: 0.0}\n"
    "truth:\n"
    "  xi: [-0.5, -0.745407]\n"  // 150 kg at 0.62 m
    "  seed: 3\n"
    "  vehicle: {bar_mass: 590.0, spring_linear_left: 20100.0, spring_linear_right: 18600.0,\n"
    "            bar_inertia: 66.5}\n"
    "health: {predictive_check: false}\n";

const char* kShipped =
    "filter:\n"
    "  update: square_root\n"
    "  relinearize: {shrink: 0.3, width: 2.0, max_restarts: 10, max_samples: 1000,\n"
    "                prior_correction: true}\n"
    "  es_mda: {alphas: [32.0, 16.0, 8.0, 4.0, 1.8823529411764706], restarts: 4, width: 1.5,\n"
    "           covariance: local}\n";

const char* kPlain =
    "filter:\n"
    "  update: square_root\n"
    "  es_mda: {alphas: [32.0, 16.0, 8.0, 4.0, 1.8823529411764706]}\n";

struct Ratio {
  double stddev, offset;  // filter std / reference std; (filter mean - reference mean) / reference std
};

TEST(RidgeReference, ShippedSettingsMatchTheConvergedReference) {
  const EstimatorConfig shipped = parseConfigString(std::string(kRidge) + kShipped, "ridge.yaml");
  const EstimatorConfig plain = parseConfigString(std::string(kRidge) + kPlain, "ridge.yaml");
  const auto model = makeModel(shipped, makeRoad(shipped));
  const MeasurementSeries series = synthesizeFromConfig(shipped, *model, shipped.truth.seed);
  const ParameterMapping mapping(*model, shipped.uncertain);
  McmcSettings ms;
  ms.sampler = McmcSampler::kConditionalLaplace;
  ms.chains = 4;
  ms.samples = 5000;
  const McmcReference ref =
      runMcmcReference(*model, mapping, series, shipped.measurement.noise, shipped.integration, 2,
                       {Eigen::VectorXd::Zero(mapping.count())}, ms);
  std::printf("reference: M %.2f +- %.2f kg, d_CG %.4f +- %.4f m, R-hat <= %.4f, ESS >= %.0f, "
              "%ld simulations, %.1f s\n",
              ref.mean[0], ref.stddev[0], ref.mean[1], ref.stddev[1], ref.r_hat.maxCoeff(),
              ref.effective_size.minCoeff(), ref.simulations, ref.seconds);
  ASSERT_LE(ref.r_hat.maxCoeff(), 1.01);
  ASSERT_GE(ref.effective_size.minCoeff(), 1000.0);
  // The ridge: M's std comes from the body mass's tolerance (580 kg x 3 %,
  // Beta(2, 2): 7.8 kg), not from the readings.
  EXPECT_GT(ref.stddev[0], 5.0);
  const auto ratio = [&](const OfflineResult& r, int i) {
    return Ratio{r.parameters[i].stddev / ref.stddev[i],
                 (r.parameters[i].mean - ref.mean[i]) / ref.stddev[i]};
  };
  for (const EstimationMethod method : {EstimationMethod::kOneStep, EstimationMethod::kEsMda}) {
    const OfflineResult s = runOfflineEstimation(shipped, series, model, method, 1);
    const OfflineResult p = runOfflineEstimation(plain, series, model, method, 1);
    for (int i = 0; i < 2; ++i) {
      const Ratio a = ratio(s, i), b = ratio(p, i);
      std::printf("%s %s: shipped std %.3f of the reference's, mean %+.3f reference std; "
                  "without: %.3f, %+.3f\n",
                  toString(method).c_str(), mapping.names()[i].c_str(), a.stddev, a.offset,
                  b.stddev, b.offset);
      EXPECT_GT(a.stddev, 0.8) << toString(method) << " " << i;
      EXPECT_LT(a.stddev, 1.25) << toString(method) << " " << i;
      EXPECT_LT(std::abs(a.offset), 0.5) << toString(method) << " " << i;
    }
    EXPECT_TRUE(s.healthy) << toString(method);
  }
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
