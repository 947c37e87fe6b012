// Configuration schema: the paper's files load with their values, and each
// kind of bad input is refused with a message naming the key.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "pc_ekf/io/estimator_config.h"
#include "pc_ekf/model/roll_plane_model.h"
#include "pc_ekf/pc/collocation_design.h"
#include "pc_ekf/pc/polynomial_basis.h"

namespace pc_ekf {
namespace {

const std::string kDir = std::string(PC_EKF_SOURCE_DIR) + "/config/";

std::string errorOf(const std::string& yaml) {
  try {
    parseConfigString(yaml, "bad.yaml");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

const char* kMinimal =
    "uncertain:\n"
    "  - {name: added_mass, nominal: 200.0, relative_range: 0.5, germ: {family: beta, alpha: 2, "
    "beta: 2}}\n"
    "  - {name: added_mass_position, nominal: 0.762, relative_range: 0.25}\n";

TEST(Config, SpeedBumpFileHoldsThePaperSettings) {
  const EstimatorConfig c = loadConfigFile(kDir + "speed_bump.yaml");
  EXPECT_DOUBLE_EQ(VehicleParameters::from(*c.model).bar_mass, 580.0);
  EXPECT_DOUBLE_EQ(VehicleParameters::from(*c.model).tyre_stiffness[1], 96319.76);
  EXPECT_DOUBLE_EQ(VehicleParameters::from(*c.model).spring_cubic[0], 1e5);
  ASSERT_EQ(c.uncertain.size(), 2u);
  EXPECT_EQ(c.uncertain[1].name, "added_mass_position");
  EXPECT_DOUBLE_EQ(c.uncertain[1].relative_range, 0.25);
  EXPECT_EQ(c.pc_order, 4);
  EXPECT_EQ(c.collocation.points, 30);
  EXPECT_EQ(c.road.source, RoadSource::kSpeedBump);
  EXPECT_EQ(c.sampling.samples, 10);
  EXPECT_DOUBLE_EQ(c.sampling.interval(), 0.3);
  EXPECT_EQ(c.update, UpdateRule::kSquareRoot);
  const Eigen::VectorXd truth =
      c.parameterValues(Eigen::Map<const Eigen::VectorXd>(c.truth.xi.data(), 2));
  EXPECT_NEAR(truth[0], 223.26, 1e-9);
  EXPECT_NEAR(truth[1], 0.762 * (1 - 0.25 * 0.3875), 1e-12);
}

TEST(Config, SineFilesSelectTheSineRoadAndTheLinearVariant) {
  const EstimatorConfig sine = loadConfigFile(kDir + "sine_1hz.yaml");
  EXPECT_EQ(sine.road.source, RoadSource::kSine);
  EXPECT_DOUBLE_EQ(sine.road.sine.amplitude, 0.05);
  EXPECT_EQ(VehicleParameters::from(*sine.model).damper, DamperLaw::kTanh);
  const EstimatorConfig linear = loadConfigFile(kDir + "sine_1hz_linear.yaml");
  EXPECT_EQ(VehicleParameters::from(*linear.model).damper, DamperLaw::kLinear);
  EXPECT_DOUBLE_EQ(VehicleParameters::from(*linear.model).spring_cubic[0], 0.0);
  EXPECT_DOUBLE_EQ(VehicleParameters::from(*linear.model).spring_cubic[1], 0.0);
}

TEST(Config, MinimalFileTakesDefaults) {
  const EstimatorConfig c = parseConfigString(kMinimal, "min.yaml");
  EXPECT_EQ(c.uncertain[1].germ.family, GermFamily::kBeta);
  EXPECT_EQ(c.truth.xi.size(), 2u);
  EXPECT_EQ(c.measurement.channels.size(), 4u);
  EXPECT_DOUBLE_EQ(c.measurement.noise.r_floor, 1e-12);
}

TEST(Config, NegativeMassIsRefusedNamingTheKey) {
  const std::string e = errorOf(std::string("vehicle: {bar_mass: -5}\n") + kMinimal);
  EXPECT_NE(e.find("bad.yaml"), std::string::npos) << e;
  EXPECT_NE(e.find("vehicle.bar_mass"), std::string::npos) << e;
  EXPECT_NE(e.find("-5"), std::string::npos) << e;
  EXPECT_NE(e.find("positive"), std::string::npos) << e;
  const std::string added = errorOf(std::string("vehicle: {added_mass: -1}\n") + kMinimal);
  EXPECT_NE(added.find("vehicle.added_mass"), std::string::npos) << added;
}

// Without relative_range the parameter would be fixed at its nominal
// (value = nominal (1 + 0 xi)) while reported as estimated: refused.
TEST(Config, UncertainEntryNeedsItsRelativeRange) {
  const std::string e = errorOf(
      "uncertain:\n  - {name: added_mass, relative_range: 0.5}\n  - {name: bar_mass}\n");
  EXPECT_NE(e.find("uncertain[1].relative_range"), std::string::npos) << e;
  EXPECT_NE(e.find("(absent)"), std::string::npos) << e;
  EXPECT_NE(errorOf("uncertain: [{name: bar_mass, relative_range: 0}]\n").find("positive"),
            std::string::npos);
}

// Nothing to estimate: neither uncertain: nor tolerances: is refused.
TEST(Config, AConfigNeedsSomethingToEstimate) {
  EXPECT_NE(errorOf("pc: {order: 2}\n").find("'uncertain'"), std::string::npos);
  EXPECT_NE(errorOf("tolerances: {bar_mass: 0}\n").find("'tolerances'"), std::string::npos);
}

TEST(Config, UnknownKeyIsRefusedNamingTheKey) {
  const std::string e = errorOf(std::string("vehicle: {bar_mas: 580}\n") + kMinimal);
  EXPECT_NE(e.find("vehicle.bar_mas"), std::string::npos) << e;
  EXPECT_NE(e.find("unknown key"), std::string::npos) << e;
  const std::string top = errorOf(std::string("sampeling: {samples: 3}\n") + kMinimal);
  EXPECT_NE(top.find("'sampeling'"), std::string::npos) << top;
}

TEST(Config, WrongSizeListIsRefusedNamingTheKey) {
  const std::string e = errorOf(std::string("truth: {xi: [0.1, 0.2, 0.3]}\n") + kMinimal);
  EXPECT_NE(e.find("truth.xi"), std::string::npos) << e;
  EXPECT_NE(e.find("a list of 2 numbers"), std::string::npos) << e;
  const std::string alphas =
      errorOf(std::string("filter: {es_mda: {alphas: [2, 2, 2]}}\n") + kMinimal);
  EXPECT_NE(alphas.find("filter.es_mda.alphas"), std::string::npos) << alphas;
}

TEST(Config, EsMdaCovarianceIsPassesOrLocal) {
  const std::string e =
      errorOf(std::string("filter: {es_mda: {covariance: exact}}\n") + kMinimal);
  EXPECT_NE(e.find("filter.es_mda.covariance"), std::string::npos) << e;
  EXPECT_NE(e.find("passes or local"), std::string::npos) << e;
  EXPECT_FALSE(parseConfigString(kMinimal, "ok.yaml").es_mda.local_covariance);
  EXPECT_TRUE(parseConfigString(std::string("filter: {es_mda: {covariance: local}}\n") + kMinimal,
                                "ok.yaml")
                  .es_mda.local_covariance);
}

TEST(Config, TooFewCollocationPointsAreRefusedNamingTheKey) {
  const std::string e = errorOf(std::string("collocation: {points: 10}\n") + kMinimal);
  EXPECT_NE(e.find("collocation.points"), std::string::npos) << e;
  EXPECT_NE(e.find("S = 15"), std::string::npos) << e;
  // Order 2 needs only 6 points.
  EXPECT_NO_THROW(parseConfigString(std::string("pc: {order: 2}\ncollocation: {points: 6}\n") +
                                        kMinimal, "ok.yaml"));
}

TEST(Config, TheRelativeWalkIsLeftOutAtAStop) {
  // drift [2, 0] kg and 1e-3 of d_CG's nominal: while driving both, in
  // quadrature; over an interval ending at a stop filter.drift alone.
  const EstimatorConfig c = parseConfigString(
      std::string("filter: {drift: [2.0, 0.0], drift_relative: [1.0e-3, 1.0e-3]}\n") + kMinimal,
      "ok.yaml");
  ASSERT_EQ(c.safeguards.drift.size(), 2);
  EXPECT_DOUBLE_EQ(c.safeguards.drift[0], std::hypot(2.0, 0.2));
  EXPECT_DOUBLE_EQ(c.safeguards.drift[1], 0.762e-3);
  ASSERT_EQ(c.safeguards.drift_standing.size(), 2);
  EXPECT_EQ(c.safeguards.drift_standing[0], 2.0);
  EXPECT_EQ(c.safeguards.drift_standing[1], 0.0);
  // Without a relative share nothing differs at a stop.
  const EstimatorConfig absolute =
      parseConfigString(std::string("filter: {drift: [2.0, 0.0]}\n") + kMinimal, "ok.yaml");
  EXPECT_EQ(absolute.safeguards.drift_standing.size(), 0);
}

TEST(Config, NestedSparseGridKey) {
  EXPECT_FALSE(parseConfigString(kMinimal, "ok.yaml").collocation.nested);
  const EstimatorConfig c = parseConfigString(
      std::string("collocation: {sequence: smolyak, level: 4, nested: true}\n") + kMinimal,
      "ok.yaml");
  EXPECT_TRUE(c.collocation.nested);
  const std::string e = errorOf(std::string("collocation: {nested: true}\n") + kMinimal);
  EXPECT_NE(e.find("collocation.nested"), std::string::npos) << e;  // halton has no rules to nest
}

TEST(Config, TruncationKeys) {
  // Default: total degree, the paper's S = 15.
  EXPECT_EQ(parseConfigString(kMinimal, "ok.yaml").pc_truncation.kind,
            TruncationKind::kTotalDegree);
  const EstimatorConfig c = parseConfigString(
      std::string("pc: {order: 4, truncation: hyperbolic, q_norm: 0.5}\ncollocation: {points: "
                  "10}\n") +
          kMinimal,
      "ok.yaml");  // S = 10 at q = 0.5: 10 points suffice
  EXPECT_EQ(c.pc_truncation.kind, TruncationKind::kHyperbolic);
  EXPECT_DOUBLE_EQ(c.pc_truncation.q_norm, 0.5);
  std::string e = errorOf(std::string("pc: {truncation: hyperbolic, q_norm: 0.5}\n"
                                      "collocation: {points: 9}\n") +
                          kMinimal);
  EXPECT_NE(e.find("collocation.points"), std::string::npos) << e;
  EXPECT_NE(e.find("S = 10"), std::string::npos) << e;
  e = errorOf(std::string("pc: {truncation: cross}\n") + kMinimal);
  EXPECT_NE(e.find("pc.truncation"), std::string::npos) << e;
  EXPECT_NE(e.find("total_degree or hyperbolic"), std::string::npos) << e;
  for (const char* q : {"0", "1.5", "-0.5"}) {
    e = errorOf(std::string("pc: {truncation: hyperbolic, q_norm: ") + q + "}\n" + kMinimal);
    EXPECT_NE(e.find("pc.q_norm"), std::string::npos) << q << ": " << e;
  }
  e = errorOf(std::string("pc: {q_norm: 0.5}\n") + kMinimal);  // total degree has no q
  EXPECT_NE(e.find("pc.q_norm"), std::string::npos) << e;
}

TEST(Config, ScrambledHaltonKeys) {
  const EstimatorConfig c = parseConfigString(
      std::string("collocation: {sequence: scrambled_halton, seed: 9}\n") + kMinimal, "ok.yaml");
  EXPECT_EQ(c.collocation.sequence, PointSequence::kScrambledHalton);
  EXPECT_EQ(c.collocation.seed, 9u);
  // auto with a point count is plain Halton at this dimension (n <= 12).
  EXPECT_EQ(parseConfigString(std::string("collocation: {sequence: auto, points: 30}\n") + kMinimal,
                              "ok.yaml")
                .collocation.sequence,
            PointSequence::kHalton);
  EXPECT_EQ(parseConfigString(kMinimal, "ok.yaml").collocation.seed, 1u);
  const std::string e = errorOf(std::string("collocation: {sequence: sobol}\n") + kMinimal);
  EXPECT_NE(e.find("scrambled_halton"), std::string::npos) << e;
}

// sequence auto without a point count: the tensor Gauss rule with order + 1
// nodes per germ where it has no more nodes than the 30 default Halton
// points, else Halton (scrambled above 12 germs); a count, start_index or
// seed keeps Halton, the count being its Q.
TEST(Config, AutoTakesTheTensorGaussRuleWhereItIsNoCostlier) {
  const auto design = [](const std::string& yaml) {
    return parseConfigString(yaml + kMinimal, "ok.yaml").collocation;
  };
  for (const char* pc : {"", "pc: {order: 4}\n"}) {  // the paper case: 5 x 5 = 25 <= 30
    for (const char* col : {"", "collocation: {sequence: auto}\n"}) {
      const CollocationConfig d = design(std::string(pc) + col);
      EXPECT_EQ(d.sequence, PointSequence::kGauss) << pc << col;
      EXPECT_EQ(d.points, 5) << pc << col;
      EXPECT_EQ(d.batchPoints(), 5) << pc << col;
      EXPECT_EQ(d.projection, ProjectionMethod::kAuto) << pc << col;  // quadrature for gauss
    }
  }
  EXPECT_EQ(design("pc: {order: 3}\n").points, 4);
  EXPECT_EQ(design("pc: {order: 3}\n").sequence, PointSequence::kGauss);
  // 6 x 6 = 36 > 30: the 30 Halton points.
  EXPECT_EQ(design("pc: {order: 5}\n").sequence, PointSequence::kHalton);
  EXPECT_EQ(design("pc: {order: 5}\n").points, 30);
  // A Halton setting keeps Halton, with the given count as Q.
  for (const char* col :
       {"collocation: {points: 30}\n", "collocation: {sequence: auto, points: 25}\n",
        "collocation: {batch_points: 40}\n", "collocation: {start_index: 2}\n",
        "collocation: {seed: 3}\n"}) {
    EXPECT_EQ(design(col).sequence, PointSequence::kHalton) << col;
  }
  EXPECT_EQ(design("collocation: {points: 25}\n").points, 25);
  EXPECT_EQ(design("collocation: {batch_points: 40}\n").points, 30);
  EXPECT_EQ(design("collocation: {batch_points: 40}\n").batchPoints(), 40);
  // Projection and the other keys leave the choice alone.
  EXPECT_EQ(design("collocation: {projection: regression}\n").sequence, PointSequence::kGauss);
  EXPECT_EQ(design("collocation: {projection: quadrature}\n").sequence, PointSequence::kGauss);
  EXPECT_EQ(design("collocation: {threads: 2, max_condition: 1e6}\n").sequence,
            PointSequence::kGauss);

  // Three germs: 3^3 = 27 at order 2; 5^3 = 125 at order 4 keeps Halton
  // (whose 30 points are then too few for S = 35, as before).
  const std::string three = std::string(kMinimal) + "tolerances: {spring_linear_left: 0.1}\n";
  const EstimatorConfig c3 = parseConfigString("pc: {order: 2}\n" + three, "ok.yaml");
  EXPECT_EQ(c3.collocation.sequence, PointSequence::kGauss);
  EXPECT_EQ(c3.collocation.points, 3);
  const std::string e = errorOf(three);
  EXPECT_NE(e.find("collocation.points"), std::string::npos) << e;
  EXPECT_NE(e.find("S = 35"), std::string::npos) << e;
  // Four germs, order 1: 2^4 = 16; five: 2^5 = 32 > 30.
  const auto orderOne = [](const std::string& tolerances) {
    return parseConfigString(std::string("pc: {order: 1}\n") + kMinimal + "tolerances: {" +
                                 tolerances + "}\n",
                             "ok.yaml");
  };
  const EstimatorConfig c4 = orderOne("spring_linear_left: 0.1, damping_left: 0.1");
  EXPECT_EQ(c4.collocation.sequence, PointSequence::kGauss);
  EXPECT_EQ(c4.collocation.points, 2);
  const EstimatorConfig c5 =
      orderOne("spring_linear_left: 0.1, damping_left: 0.1, tyre_stiffness_left: 0.1");
  EXPECT_EQ(c5.collocation.sequence, PointSequence::kHalton);
  EXPECT_EQ(c5.collocation.points, 30);
}

// The batch methods' basis may be larger (batch_tolerance_interactions) but
// stays within total degree p, which the order + 1 Gauss nodes per germ
// resolve: auto's rule serves both designs.
TEST(Config, AutoGaussServesTheBatchDesign) {
  const EstimatorConfig c = parseConfigString(
      "pc: {order: 2, tolerance_interactions: false, batch_tolerance_interactions: true}\n"
      "uncertain:\n"
      "  - {name: added_mass, nominal: 200.0, relative_range: 0.5}\n"
      "tolerances: {spring_linear_left: 0.1, damping_left: 0.1}\n",
      "ok.yaml");
  EXPECT_EQ(c.collocation.sequence, PointSequence::kGauss);
  EXPECT_EQ(c.collocation.points, 3);
  EXPECT_EQ(c.collocation.batchPoints(), 3);
  for (const BasisTruncation& t : {c.pc_truncation, c.batchTruncation()}) {
    const PolynomialBasis basis(c.germs(), c.pc_order, t);
    const CollocationDesign d(basis, c.collocation.sequence, c.collocation.batchPoints());
    EXPECT_EQ(d.pointCount(), 27);
    EXPECT_EQ(d.projection(), ProjectionMethod::kQuadrature);
    EXPECT_NEAR(d.conditionNumber(), 1.0, 1e-9);  // exact to degree 2p: orthonormal columns
  }
  EXPECT_EQ(PolynomialBasis(c.germs(), 2, c.batchTruncation()).size(), 10);  // total degree
  EXPECT_EQ(PolynomialBasis(c.germs(), 2, c.pc_truncation).size(), 9);  // no tolerance product
}

TEST(Config, SparseGridKeys) {
  const EstimatorConfig c = parseConfigString(
      std::string(
          "pc: {order: 3}\ncollocation: {sequence: smolyak, threads: 2, loo_warning: 0.05}\n") +
          kMinimal,
      "ok.yaml");
  EXPECT_EQ(c.collocation.sequence, PointSequence::kSmolyak);
  EXPECT_EQ(c.collocation.designCount(c.pc_order), 3);  // level defaults to the order
  EXPECT_EQ(c.collocation.threads, 2);
  EXPECT_DOUBLE_EQ(c.collocation.loo_warning, 0.05);
  EXPECT_EQ(parseConfigString(
                std::string("collocation: {sequence: smolyak, level: 5}\n") + kMinimal, "ok.yaml")
                .collocation.designCount(4),
            5);
  // The quadrature projection needs level >= order; halton has no quadrature.
  std::string e =
      errorOf(std::string("collocation: {sequence: smolyak, level: 3, projection: quadrature}\n") +
              kMinimal);
  EXPECT_NE(e.find("collocation.level"), std::string::npos) << e;
  e = errorOf(std::string("collocation: {sequence: halton, projection: quadrature}\n") + kMinimal);
  EXPECT_NE(e.find("collocation.projection"), std::string::npos) << e;
  e = errorOf(std::string("collocation: {projection: lsq}\n") + kMinimal);
  EXPECT_NE(e.find("collocation.projection"), std::string::npos) << e;
  e = errorOf(std::string("collocation: {threads: -1}\n") + kMinimal);
  EXPECT_NE(e.find("collocation.threads"), std::string::npos) << e;
}

TEST(Config, BadValuesAreRefusedNamingTheKey) {
  EXPECT_NE(errorOf(std::string("road: {source: gravel}\n") + kMinimal).find("road.source"),
            std::string::npos);
  EXPECT_NE(errorOf(std::string("measurement: {channels: [u1, w3]}\n") + kMinimal)
                .find("measurement.channels"),
            std::string::npos);
  EXPECT_NE(errorOf(std::string("sampling: {samples: 2.5}\n") + kMinimal).find("sampling.samples"),
            std::string::npos);
  EXPECT_NE(errorOf(std::string("truth: {xi: [1.5, 0]}\n") + kMinimal).find("truth.xi[0]"),
            std::string::npos);
  EXPECT_NE(errorOf("uncertain:\n  - {name: wheel_base, relative_range: 0.1}\n")
                .find("uncertain[0].name"),
            std::string::npos);
  EXPECT_NE(errorOf(std::string("vehicle: {added_mass_position: 2.0}\n") + kMinimal)
                .find("vehicle.added_mass_position"),
            std::string::npos);
  const std::string yaml = errorOf("vehicle: {bar_mass: [1,\n");
  EXPECT_NE(yaml.find("line"), std::string::npos) << yaml;
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
