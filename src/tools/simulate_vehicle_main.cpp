// simulate_vehicle: static equilibrium and noise-free response of the
// roll-plane model at the nominal and the true parameters of a config
// (a quick look at the model without any estimator). The truth includes
// truth.vehicle and truth.schedule (not the sensor or timing imperfections).
#include <cmath>
#include <cstdio>
#include <iostream>
#include <string>

#include "filter/trajectory_simulation.h"
#include "io/estimation_setup.h"

namespace {

void printEquilibrium(const char* label, const pc_ekf::VehicleParameters& p) {
  const pc_ekf::StaticEquilibrium e = pc_ekf::solveStaticEquilibrium(p);
  std::printf("%s: M = %.2f kg, d_CG = %.4f m -> theta_s = %.4f deg, h2 - h1 = %.5f m\n", label,
              p.added_mass, p.added_mass_position, e.roll_angle * 180.0 / M_PI,
              e.height[1] - e.height[0]);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace pc_ekf;
  if (argc != 3 || std::string(argv[1]) != "--config") {
    std::cerr << "usage: simulate_vehicle --config FILE.yaml\n";
    return 2;
  }
  try {
    const EstimatorConfig c = loadConfigFile(argv[2]);
    const auto model = makeModel(c, makeRoad(c));
    const auto truth = truthModel(c, *model);
    const VehicleParameters& truth_laws = c.truth.vehicle ? *c.truth.vehicle : c.vehicle;
    const SyntheticDataSettings s = syntheticSettings(c, *truth, c.truth.seed);
    const std::vector<double>& times = s.times;
    const Eigen::VectorXd cases[2] = {model->nominalParameters(), truthParameters(c, *model)};
    const MechanicalModel* models[2] = {model.get(), truth.get()};
    const char* labels[2] = {"nominal", "truth"};
    for (int i = 0; i < 2; ++i) {
      const VehicleParameters& laws = i == 0 ? c.vehicle : truth_laws;
      printEquilibrium(labels[i], VehicleParameters::fromVector(cases[i], laws));
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
          printEquilibrium(from.c_str(), VehicleParameters::fromVector(change.params, laws));
        }
      }
      const auto z = simulateScheduled(*models[i], cases[i],
                                       i == 1 ? s.schedule : std::vector<ParameterChange>{}, times,
                                       c.integration);
      std::printf("  %6s %11s %11s %11s %11s\n", "t [s]", "u1 [m]", "u2 [m]", "v1 [m/s]", "v2 [m/s]");
      for (std::size_t k = 0; k < times.size(); ++k) {
        std::printf("  %6.2f %11.6f %11.6f %11.6f %11.6f\n", times[k], z[k](0, 0), z[k](1, 0),
                    z[k](2, 0), z[k](3, 0));
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
