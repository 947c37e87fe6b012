// Static equilibrium with heights and an anti-roll bar (docs/models.md) where
// the elevated masses' moment g S approaches or exceeds the roll stiffness:
// a point with no stable equilibrium is refused by invalidReason (the
// estimators drop it) instead of failing the run, and every other point is
// solved to a stable equilibrium (Newton, else a bracket on the tilt).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "pc_ekf/model/roll_plane_model.h"
#include "pc_ekf/model/roll_plane_road_free.h"

namespace pc_ekf {
namespace {

std::shared_ptr<const ContactRoad> flat() {
  SineSettings s;
  s.amplitude = 0.0;
  return std::make_shared<SineRoad>(s);
}

VehicleParameters elevated() {
  VehicleParameters p;
  p.added_mass = 200.0;
  p.added_mass_position = 0.762;
  p.body_cg_height = 0.25;
  p.added_mass_height = 0.40;
  p.mount_height = 0.40;
  p.wheel_radius = 0.30;
  p.imu_height = 0.10;
  p.anti_roll_bar = 8000.0;
  return p;
}

// A collocation point a road-free run met (heights, bar, a wandering
// estimate): the right tyre at 822 N/m cannot carry g S / L = 1357 N per unit
// tilt; Newton on the equilibrium used to fail and end the run.
VehicleParameters softRightTyre() {
  VehicleParameters p = elevated();
  p.bar_mass = 592.82589260423163;
  p.unsprung_mass[0] = 36.538520123233901;
  p.unsprung_mass[1] = 37.421402418860836;
  p.damping[0] = 716.32770750861653;
  p.damping[1] = 736.8807890103451;
  p.spring_linear[0] = 20277.853487135442;
  p.spring_linear[1] = 27303.746389283249;
  p.spring_cubic[0] = 104721.60902500318;
  p.spring_cubic[1] = 50923.032472220504;
  p.bar_length = 1.5211556841400669;
  p.bar_inertia = 73.559414353932652;
  p.tyre_stiffness[0] = 89597.185918619187;
  p.tyre_stiffness[1] = 822.21128400354064;
  p.added_mass = 199.05122148949755;
  p.added_mass_position = 0.76198942003688097;
  p.imu_position = 0.76395290967831797;
  p.body_cg_height = 0.2223059285157544;
  p.added_mass_height = 0.39508423330294434;
  p.anti_roll_bar = 8486.113522744301;
  return p;
}

// The equilibrium's equations at the solved point, and the tilt's restoring
// slope g'(t) = L - g S / L (roll compliance of springs, bar and tyres).
void expectStableEquilibrium(const VehicleParameters& p, const StaticEquilibrium& e) {
  const double g = p.gravity, length = p.bar_length;
  const double moment = p.bar_mass * p.body_cg_height + p.added_mass * p.added_mass_height;
  const double t = (e.height[0] - e.height[1]) / length;
  const double weight = (p.bar_mass + p.added_mass) * g;
  EXPECT_NEAR(e.load[0] + e.load[1], weight, 1e-9 * weight);
  EXPECT_NEAR(e.load[0], weight * (length - e.combined_cg) / length - g * moment / length * t,
              1e-9 * weight);
  double s[2];
  const double twist = p.anti_roll_bar * (e.spring_compression[0] - e.spring_compression[1]);
  for (int i = 0; i < 2; ++i) {
    const double d = e.spring_compression[i];
    s[i] = p.spring_linear[i] + 3.0 * p.spring_cubic[i] * d * d;
    const double force = p.spring_linear[i] * d + p.spring_cubic[i] * d * d * d;
    EXPECT_NEAR(force + (i == 0 ? twist : -twist), e.load[i], 1e-8 * weight);
    EXPECT_NEAR(e.height[i],
                -(d + (e.load[i] + p.unsprung_mass[i] * g) / p.tyre_stiffness[i]), 1e-12);
  }
  const double springs = (s[0] + s[1]) / (s[0] * s[1] + p.anti_roll_bar * (s[0] + s[1]));
  const double tyres = 1.0 / p.tyre_stiffness[0] + 1.0 / p.tyre_stiffness[1];
  EXPECT_GT(length - g * moment / length * (springs + tyres), 0.0);
}

TEST(RollPlaneHeightsStability, NoStableEquilibriumIsRefusedPerPoint) {
  const VehicleParameters p = softRightTyre();
  try {
    solveStaticEquilibrium(p);
    FAIL() << "expected a refusal";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no stable equilibrium"), std::string::npos) << e.what();
  }
  const RollPlaneModel model(elevated(), flat());
  const std::string why = model.invalidReason(p.toVector());
  EXPECT_NE(why.find("no stable static equilibrium"), std::string::npos) << why;
  // The road-free model asks the same, so its estimators drop the point.
  const std::vector<double> times{0.0, 0.005};
  const std::vector<std::vector<double>> zeros(4, std::vector<double>(2, 0.0));
  const RollPlaneRoadFreeModel road_free(
      elevated(),
      std::make_shared<ReadingInputs>(std::vector<std::string>{"u1", "u2", "v1", "v2"}, times, zeros),
      ZeroConvention::kTare);
  EXPECT_EQ(road_free.invalidReason(p.toVector()), why);
  // The nominal vehicle and the same point with its tyre back are usable.
  EXPECT_EQ(model.invalidReason(elevated().toVector()), "");
  VehicleParameters back = p;
  back.tyre_stiffness[1] = 96319.76;
  EXPECT_EQ(model.invalidReason(back.toVector()), "");
  expectStableEquilibrium(back, solveStaticEquilibrium(back));
}

TEST(RollPlaneHeightsStability, EveryPointSolvedStablyOrRefused) {
  // Springs, tyres, bar and heights scaled over two decades each way: a point
  // is usable (invalidReason "") exactly when the solve gives a stable point
  // that meets the equations; else the solve throws, never a non-answer.
  const RollPlaneModel model(elevated(), flat());
  std::uint64_t state = 12345;
  const auto uniform = [&state]() {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(state >> 11) * 0x1.0p-53;
  };
  const auto factor = [&uniform]() { return std::pow(10.0, 4.0 * uniform() - 2.0); };
  int usable = 0, refused = 0;
  for (int n = 0; n < 3000; ++n) {
    VehicleParameters p = elevated();
    for (int i = 0; i < 2; ++i) {
      p.spring_linear[i] *= factor();
      p.spring_cubic[i] *= uniform() < 0.2 ? 0.0 : factor();
      p.tyre_stiffness[i] *= factor();
    }
    p.anti_roll_bar *= uniform() < 0.2 ? 0.0 : factor();
    p.body_cg_height = 2.0 * uniform() - 0.5;
    p.added_mass_height = 3.0 * uniform() - 0.5;
    p.added_mass = 600.0 * uniform();
    p.added_mass_position = p.bar_length * uniform();
    const std::string why = model.invalidReason(p.toVector());
    if (why.empty()) {
      ++usable;
      StaticEquilibrium e;
      ASSERT_NO_THROW(e = solveStaticEquilibrium(p)) << n;
      expectStableEquilibrium(p, e);
    } else {
      ++refused;
      EXPECT_NE(why.find("no stable"), std::string::npos) << why;
      EXPECT_THROW(solveStaticEquilibrium(p), std::runtime_error) << n;
    }
  }
  EXPECT_GT(usable, 1000);
  EXPECT_GT(refused, 100);
}

TEST(RollPlaneHeightsStability, BoundaryOfTheTyresIsRefused) {
  // g S / L (1/k_t1 + 1/k_t2) just above L: refused in closed form.
  VehicleParameters p = elevated();
  const double moment = p.bar_mass * p.body_cg_height + p.added_mass * p.added_mass_height;
  const double shift = p.gravity * moment / p.bar_length;
  p.tyre_stiffness[0] = p.tyre_stiffness[1] = 2.0 * shift / p.bar_length * 0.99;
  const RollPlaneModel model(elevated(), flat());
  EXPECT_NE(model.invalidReason(p.toVector()).find("tyres' roll stiffness"), std::string::npos);
  EXPECT_THROW(solveStaticEquilibrium(p), std::runtime_error);
  // Stiffer tyres with the springs softened to the edge: solved or refused, never a crash.
  p.tyre_stiffness[0] = p.tyre_stiffness[1] = 2.0 * shift / p.bar_length * 1.5;
  const std::string why = model.invalidReason(p.toVector());
  if (why.empty()) {
    expectStableEquilibrium(p, solveStaticEquilibrium(p));
  } else {
    EXPECT_THROW(solveStaticEquilibrium(p), std::runtime_error);
  }
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
