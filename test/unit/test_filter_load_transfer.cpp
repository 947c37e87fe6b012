// The load transfer ratio (docs/models.md, "Rollover outputs") of the
// road-free roll plane, from the readings: zero at rest with the load in the
// middle, the static moment balance's closed form with the load off-centre,
// and in a steady turn the rigid vehicle's a_y h_cg / (g L / 2) plus the
// body's roll; and the derived quantities' PDFs (the sampler the node's
// parameter_pdf and estimate_offline's pdfs.csv use) against their expansions.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "pc_ekf/filter/rollover_quantities.h"
#include "pc_ekf/model/integrator.h"
#include "pc_ekf/model/road_input.h"
#include "pc_ekf/model/horizontal_motion.h"
#include "pc_ekf/model/roll_plane_model.h"
#include "pc_ekf/model/roll_plane_road_free.h"
#include "pc_ekf/pc/pc_statistics.h"
#include "pc_ekf/pc/pdf_sampler.h"

namespace pc_ekf {
namespace {

// Readings held at `u1 u2 v1 v2` (and speed, gyro_z when given) over 1 s.
std::shared_ptr<const ReadingInputs> held(const std::vector<double>& values) {
  std::vector<std::string> names{"u1", "u2", "v1", "v2"};
  if (values.size() == 6) {
    names.push_back("speed");
    names.push_back("gyro_z");
  }
  std::vector<double> times;
  std::vector<std::vector<double>> columns(values.size());
  for (int k = 1; k <= 100; ++k) {
    times.push_back(0.01 * k);
    for (std::size_t c = 0; c < values.size(); ++c) columns[c].push_back(values[c]);
  }
  return std::make_shared<ReadingInputs>(names, times, columns);
}

VehicleParameters linearSprings(VehicleParameters p) {
  p.spring_cubic[0] = p.spring_cubic[1] = 0.0;
  return p;
}

TEST(LoadTransferRatio, ZeroAtRestWithTheLoadInTheMiddle) {
  // L = 2: the combined centre D = (m 1 + M 1) / (m + M) = 1 = L / 2 with no
  // rounding, so both sides' static loads are the same numbers.
  VehicleParameters p;
  p.bar_length = 2.0;
  p.added_mass = 300.0;
  p.added_mass_position = 1.0;
  ASSERT_EQ(p.spring_linear[0], p.spring_linear[1]);
  ASSERT_EQ(p.unsprung_mass[0], p.unsprung_mass[1]);
  for (const ZeroConvention zero : {ZeroConvention::kRest, ZeroConvention::kTare}) {
    // Tare: the readings of the loaded vehicle at rest are its extra compression.
    double u = 0.0;
    if (zero == ZeroConvention::kTare) {
      VehicleParameters empty = p;
      empty.added_mass = 0.0;
      u = solveStaticEquilibrium(empty).spring_compression[0] -
          solveStaticEquilibrium(p).spring_compression[0];
    }
    const RollPlaneRoadFreeModel m(p, held({u, u, 0.0, 0.0}), zero);
    ASSERT_TRUE(m.hasLoadTransferRatio());
    // Rest: both sides' forces are the same numbers, 0 exactly; tare: the
    // readings are a difference of compressions, 0 to round-off.
    if (zero == ZeroConvention::kRest) {
      EXPECT_EQ(m.loadTransferRatio(p.toVector(), 0.5), 0.0);
    } else {
      EXPECT_NEAR(m.loadTransferRatio(p.toVector(), 0.5), 0.0, 1e-15);
    }
  }
}

// Linear springs, no heights, the load at P: the tyre loads from the moment
// balance about the left end, F_2 = g ((m + M) D / L) + m_u g, F_1 = g (m + M)
// (L - D) / L + m_u g with (m + M) D = m L / 2 + M P.
TEST(LoadTransferRatio, StaticOffsetIsTheMomentBalance) {
  for (double position : {0.3, 0.9, 1.3}) {
    VehicleParameters p = linearSprings(VehicleParameters());
    p.added_mass = 250.0;
    p.added_mass_position = position;
    const RollPlaneRoadFreeModel m(p, held({0.0, 0.0, 0.0, 0.0}), ZeroConvention::kRest);
    const double g = p.gravity, L = p.bar_length, sprung = p.bar_mass + p.added_mass;
    const double D = (p.bar_mass * 0.5 * L + p.added_mass * position) / sprung;
    const double right = g * sprung * D / L + p.unsprung_mass[1] * g;
    const double left = g * sprung * (L - D) / L + p.unsprung_mass[0] * g;
    const double expected = (right - left) / (right + left);
    EXPECT_NEAR(m.loadTransferRatio(p.toVector(), 0.5), expected, 1e-12) << position;
    EXPECT_EQ(position > 0.5 * L, expected > 0.0);  // the load's side carries more
  }
  // Not admissible: NaN.
  VehicleParameters p;
  const RollPlaneRoadFreeModel m(p, held({0.0, 0.0, 0.0, 0.0}), ZeroConvention::kRest);
  Eigen::VectorXd bad = p.toVector();
  bad[rollPlaneRows().bar_mass] = -1.0;
  EXPECT_TRUE(std::isnan(m.loadTransferRatio(bad, 0.5)));
}

// A steady left turn on the road-given roll plane (test_model_heights.cpp's
// vehicle: heights, bar, linear springs, stiff tyres): its travel readings at
// steady state, given to the road-free model with speed and gyro_z, give the
// rigid vehicle's LTR = a_y h_cg / (g L / 2) plus the compliance: the body
// rolls out of the turn by phi, which moves its elevated masses' weight by
// S phi (S = m h_b + M h_M) to the outer side, 2 S phi / (L m_total) more.
TEST(LoadTransferRatio, SteadyTurnIsTheRigidVehiclesPlusTheBodysRoll) {
  VehicleParameters p = linearSprings(VehicleParameters());
  p.added_mass = 200.0;
  p.added_mass_position = 0.5 * p.bar_length;
  p.body_cg_height = 0.25;
  p.added_mass_height = 0.40;
  p.mount_height = 0.40;
  p.wheel_radius = 0.30;
  p.anti_roll_bar = 8000.0;
  p.tyre_stiffness[0] = p.tyre_stiffness[1] = 1e8;
  p.damper = DamperLaw::kLinear;
  p.damping[0] = p.damping[1] = 4000.0;  // settles within the run
  const double a_y = 3.0, speed = 20.0;
  SineSettings flat;
  flat.amplitude = 0.0;
  HorizontalState h;
  h.speed = speed;
  h.yaw_rate = a_y / speed;
  h.lateral = a_y;
  const RollPlaneModel road(p, std::make_shared<RoadWithMotion>(std::make_shared<SineRoad>(flat),
                                                                std::make_shared<SteadyMotion>(h)),
                            {ZeroConvention::kRest, true});
  const auto batch = road.prepare(p.toVector());
  Eigen::ArrayXXd y = batch->initialState();
  integrate(road, *batch, 0.0, 8.0, y, IntegratorSettings{2e-4, IntegrationMethod::kRk4});
  std::vector<double> readings;
  for (int c = 0; c < 4; ++c) readings.push_back(y(8 + c, 0));
  readings.push_back(speed);
  readings.push_back(a_y / speed);
  const RollPlaneRoadFreeModel m(p, held(readings), ZeroConvention::kRest);
  const double ltr = m.loadTransferRatio(p.toVector(), 0.5);

  const double g = p.gravity, L = p.bar_length;
  const double total = p.bar_mass + p.added_mass + p.unsprung_mass[0] + p.unsprung_mass[1];
  const double h_cg = ((p.bar_mass + p.added_mass) * p.mount_height +
                       p.bar_mass * p.body_cg_height + p.added_mass * p.added_mass_height +
                       (p.unsprung_mass[0] + p.unsprung_mass[1]) * p.wheel_radius) /
                      total;
  const double rigid = a_y * h_cg / (g * L / 2.0);
  // The body's roll against the axle from the travel readings (u: extension).
  const double roll = (readings[0] - readings[1]) / L;
  const double s = p.bar_mass * p.body_cg_height + p.added_mass * p.added_mass_height;
  const double compliance = 2.0 * s * std::abs(roll) / (L * total);
  EXPECT_GT(ltr, 0.0);  // a left turn loads the right tyre
  // Within the model's compliance of the rigid estimate: the rigid vehicle
  // leaves out the roll's share (here 0.006 of 0.263, 2.3 %), so the
  // tolerance is that share, with 2 % of it for the second-order terms
  // (cos(phi), the tyres' 1e-8 m/N).
  EXPECT_NEAR(ltr, rigid, 1.02 * compliance) << "rigid " << rigid << " compliance " << compliance;
  // And with the roll's share the closed form to 2 % of that share.
  EXPECT_NEAR(ltr, rigid + compliance, 0.02 * compliance + 1e-6);
}

// The rollover outputs' PDFs by the parameters' sampler: the histogram's mean
// and std (bin centres, Sheppard's correction w^2/12 for the std) against the
// expansion's within the sampler's error: 5 std / sqrt(draws) for the mean,
// 5 std / sqrt(2 draws) for the std, plus w / 20 for the binning.
TEST(DerivedPdfs, HistogramMomentsMatchTheExpansion) {
  VehicleParameters p;
  p.body_cg_height = 0.25;
  p.added_mass_height = 0.40;
  p.mount_height = 0.40;
  p.wheel_radius = 0.30;
  SineSettings flat;
  flat.amplitude = 0.0;
  const RollPlaneModel model(p, std::make_shared<SineRoad>(flat));
  const ParameterMapping mapping(
      model, {UncertainParameter{"added_mass", 200.0, 0.5, GermSpec{}},
              UncertainParameter{"added_mass_position", 0.762, 0.3, GermSpec{}}});
  ASSERT_TRUE(hasRolloverQuantities(mapping));
  const PolynomialBasis basis(mapping.germs(), 3);
  const DerivedExpansions d = rolloverExpansions(mapping, basis, mapping.priorCoefficients(basis));
  ASSERT_EQ(d.names.size(), 3u);
  const int draws = 100000, bins = 60;
  const ParameterPdfSampler sampler(basis, draws, bins, 7);
  const std::vector<Histogram> h = sampler.histograms(d.coefficients);
  ASSERT_EQ(h.size(), 3u);
  const Eigen::VectorXd mean = pcMean(d.coefficients), sd = pcStddev(d.coefficients);
  for (std::size_t i = 0; i < h.size(); ++i) {
    const Eigen::Index k = static_cast<Eigen::Index>(i);
    const Eigen::VectorXd c = h[i].centres();
    const double w = h[i].edges[1] - h[i].edges[0];
    double m1 = 0.0, m2 = 0.0, area = 0.0;
    for (Eigen::Index b = 0; b < c.size(); ++b) {
      const double mass = h[i].densities[b] * (h[i].edges[b + 1] - h[i].edges[b]);
      area += mass;
      m1 += mass * c[b];
      m2 += mass * c[b] * c[b];
    }
    EXPECT_NEAR(area, 1.0, 1e-12) << d.names[i];
    const double hist_sd = std::sqrt(std::max(0.0, m2 - m1 * m1 - w * w / 12.0));
    EXPECT_NEAR(m1, mean[k], 5.0 * sd[k] / std::sqrt(draws) + w / 20.0) << d.names[i];
    EXPECT_NEAR(hist_sd, sd[k], 5.0 * sd[k] / std::sqrt(2.0 * draws) + w / 20.0) << d.names[i];
    // The same numbers as pcHistogram with the seed (estimate_offline's pdfs.csv).
    const Histogram one = pcHistogram(basis, d.coefficients.row(k).transpose(), draws, bins, 7);
    EXPECT_EQ(one.densities, h[i].densities) << d.names[i];
  }
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
