// simulate_vehicle: static equilibrium and noise-free response of the
// config's model at the nominal and the true parameters
// (a quick look at the model without any estimator). The truth includes
// truth.vehicle and truth.schedule (not the sensor or timing imperfections).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <string>

#include "pc_ekf/filter/trajectory_simulation.h"
#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/ros/model_plugins.h"

namespace {

using pc_ekf::EstimatorConfig;

// The model's own equilibrium line (models without one: the label only).
void printEquilibrium(const EstimatorConfig& c, const char* label, const Eigen::VectorXd& params,
                      bool truth) {
  const auto& laws = truth ? *c.truthModelParameters() : *c.modelParameters();
  const std::string line = c.model_type->equilibriumSummary(laws, params);
  std::printf("%s:%s%s\n", label, line.empty() ? "" : " ", line.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  using namespace pc_ekf;
  if (argc != 3 || std::string(argv[1]) != "--config") {
    std::cerr << "usage: simulate_vehicle --config FILE.yaml\n";
    return 2;
  }
  try {
    const EstimatorConfig c = loadConfigFile(argv[2], modelRegistryWithPlugins());
    // Road-free configs simulate the vehicle on the truth's road (truth.road).
    const auto model = c.road.source == RoadSource::kNone
                           ? c.model_type->build(*c.modelParameters(), makeTruthRoad(c),
                                                 c.measurement.readings(c.model_type->description()))
                           : makeModel(c, makeRoad(c));
    const auto truth = truthModel(c, *model);
    const SyntheticDataSettings s = syntheticSettings(c, *truth, c.truth.seed);
    const std::vector<double>& times = s.times;
    const Eigen::VectorXd cases[2] = {model->nominalParameters(), truthParameters(c, *model)};
    const MechanicalModel* models[2] = {model.get(), truth.get()};
    const char* labels[2] = {"nominal", "truth"};
    for (int i = 0; i < 2; ++i) {
      printEquilibrium(c, labels[i], cases[i], i == 1);
      if (i == 1) {
        const Eigen::VectorXd est = model->nominalParameters(), tru = truth->nominalParameters();
        for (Eigen::Index j = 0; j < est.size(); ++j) {
          if (est[j] != tru[j]) {
            std::printf("  truth.vehicle: %s = %.10g (estimator: %.10g)\n",
                        model->parameterNames()[j].c_str(), tru[j], est[j]);
          }
        }
        for (const auto& change : s.schedule) {
          const std::string from = "  from t = " + std::to_string(change.time) + " s";
          printEquilibrium(c, from.c_str(), change.params, true);
        }
      }
      const auto z = simulateScheduled(*models[i], cases[i],
                                       i == 1 ? s.schedule : std::vector<ParameterChange>{}, times,
                                       c.integration);
      // The channels the model gives as built (IMU ones with readings as states).
      const auto& specs = c.model_type->description().channels();
      // Times to 0.01 s, or finer when the samples are closer (200 Hz: 0.001).
      const int decimals =
          std::max(2, static_cast<int>(std::ceil(-std::log10(c.sampling.interval()) - 1e-9)));
      const int width = 6 + decimals - 2;
      std::printf("  %*s", width, "t [s]");
      for (std::size_t ch = 0; ch < specs.size(); ++ch) {
        if (!model->channelModelled(static_cast<int>(ch))) continue;
        const std::string head = specs[ch].name + " [" + specs[ch].unit + "]";
        std::printf(" %13s", head.c_str());
      }
      std::printf("\n");
      for (std::size_t k = 0; k < times.size(); ++k) {
        std::printf("  %*.*f", width, decimals, times[k]);
        for (std::size_t ch = 0; ch < specs.size(); ++ch) {
          if (model->channelModelled(static_cast<int>(ch))) std::printf(" %13.6f", z[k](ch, 0));
        }
        std::printf("\n");
      }
    }
    return 0;
  } catch (const ConfigError& e) {
    std::cerr << "simulate_vehicle: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "simulate_vehicle: error: " << e.what() << "\n";
    return 1;
  }
}
