// The rollover outputs (docs/models.md, "Rollover outputs"): cg_height,
// static_stability_factor and rollover_threshold as PC expansions, against
// the closed form over the load's germ (high-order Gauss quadrature of the
// same function), exactness for linear functions, Monte Carlo draws of the
// function, the SSF and threshold identities, and their absence without heights.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <memory>

#include "pc_ekf/filter/rollover_quantities.h"
#include "pc_ekf/model/full_car_model.h"
#include "pc_ekf/model/road_input.h"
#include "pc_ekf/model/roll_plane_model.h"
#include "pc_ekf/model/scalar_growth_model.h"
#include "pc_ekf/pc/pc_statistics.h"

namespace pc_ekf {
namespace {

// docs/models.md's reference heights (turns.yaml's vehicle).
VehicleParameters elevated() {
  VehicleParameters p;
  p.body_cg_height = 0.25;
  p.added_mass_height = 0.40;
  p.mount_height = 0.40;
  p.wheel_radius = 0.30;
  p.anti_roll_bar = 8000.0;
  return p;
}

std::shared_ptr<const RollPlaneModel> rollPlane(const VehicleParameters& p) {
  SineSettings s;
  s.amplitude = 0.0;
  return std::make_shared<RollPlaneModel>(p, std::make_shared<SineRoad>(s));
}

// The CG height written out by hand for the roll plane's values.
double cgHeight(const VehicleParameters& p, double M, double h_M) {
  const double m = p.bar_mass, mu = p.unsprung_mass[0] + p.unsprung_mass[1];
  return ((m + M) * p.mount_height + m * p.body_cg_height + M * h_M + mu * p.wheel_radius) /
         (m + M + mu);
}

const UncertainParameter kMass{"added_mass", 200.0, 0.5, GermSpec{}};  // Beta(2, 2)

// Only M uncertain, heights fixed: cg_height is a ratio of affine functions of
// M. The projection's coefficients E[f psi_j] must equal a 60-point Gauss
// rule's (the function is smooth: converged far below 1e-12), and the mean
// and std those of the function itself up to the order-3 truncation.
TEST(RolloverQuantities, ClosedFormOverTheLoadsGerm) {
  const VehicleParameters p = elevated();
  const ParameterMapping mapping(*rollPlane(p), {kMass});
  ASSERT_TRUE(hasRolloverQuantities(mapping));
  const PolynomialBasis basis(mapping.germs(), 3);
  const DerivedExpansions d = rolloverExpansions(mapping, basis, mapping.priorCoefficients(basis));
  ASSERT_EQ(d.names, rolloverQuantityNames());
  ASSERT_EQ(d.coefficients.rows(), 3);

  const QuadratureRule rule = basis.family(0).gaussRule(60);
  Eigen::Matrix<double, 3, 4> projected = Eigen::Matrix<double, 3, 4>::Zero();
  Eigen::Vector3d mean = Eigen::Vector3d::Zero(), square = Eigen::Vector3d::Zero();
  for (Eigen::Index q = 0; q < rule.nodes.size(); ++q) {
    const double M = 200.0 * (1.0 + 0.5 * rule.nodes[q]);
    const double h = cgHeight(p, M, p.added_mass_height);
    const Eigen::Vector3d f(h, p.bar_length / (2.0 * h), p.gravity * p.bar_length / (2.0 * h));
    const Eigen::VectorXd psi = basis.evaluate(Eigen::VectorXd::Constant(1, rule.nodes[q]));
    projected += rule.weights[q] * f * psi.transpose();
    mean += rule.weights[q] * f;
    square += rule.weights[q] * f.cwiseProduct(f);
  }
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 4; ++j) {
      EXPECT_NEAR(d.coefficients(i, j), projected(i, j), 1e-12 * std::abs(projected(i, 0)))
          << d.names[i] << " term " << j;
    }
  }
  const Eigen::VectorXd pc_mean = pcMean(d.coefficients), pc_std = pcStddev(d.coefficients);
  for (int i = 0; i < 3; ++i) {
    const double stddev = std::sqrt(square[i] - mean[i] * mean[i]);
    EXPECT_NEAR(pc_mean[i], mean[i], 1e-12 * mean[i]) << d.names[i];
    EXPECT_NEAR(pc_std[i], stddev, 1e-4 * stddev) << d.names[i];
    EXPECT_GT(pc_std[i], 0.0);
  }
  // The load sits above the rest's centre of mass, so more load lifts the
  // CG: the mean lies between the light and the heavy end's heights.
  EXPECT_GT(pc_mean[0], cgHeight(p, 100.0, 0.4));
  EXPECT_LT(pc_mean[0], cgHeight(p, 300.0, 0.4));
}

// At a point (every coefficient but the mean zero) the expansions are the
// hand-computed values, and every node obeys SSF = L / (2 h), a = g SSF.
TEST(RolloverQuantities, PointValuesAndIdentities) {
  VehicleParameters p = elevated();
  p.bar_length = 1.6;
  p.gravity = 9.80665;
  const ParameterMapping mapping(*rollPlane(p), {kMass});
  const PolynomialBasis basis(mapping.germs(), 2);
  Eigen::MatrixXd point = Eigen::MatrixXd::Zero(1, basis.size());
  point(0, 0) = 250.0;
  const DerivedExpansions d = rolloverExpansions(mapping, basis, point);
  const double h = ((580.0 + 250.0) * 0.4 + 580.0 * 0.25 + 250.0 * 0.4 + 2 * 36.26 * 0.3) /
                   (580.0 + 250.0 + 2 * 36.26);
  EXPECT_NEAR(d.coefficients(0, 0), h, 1e-14);
  EXPECT_NEAR(d.coefficients(1, 0), 1.6 / (2 * h), 1e-13);
  EXPECT_NEAR(d.coefficients(2, 0), 9.80665 * 1.6 / (2 * h), 1e-12);
  EXPECT_LT(d.coefficients.rightCols(basis.size() - 1).cwiseAbs().maxCoeff(), 1e-13);

  Eigen::MatrixXd full = mapping.fullParameters(Eigen::RowVector3d(100.0, 200.0, 300.0));
  const Eigen::MatrixXd v = rolloverValues(mapping, full);
  for (int q = 0; q < 3; ++q) {
    EXPECT_DOUBLE_EQ(v(1, q), 1.6 / (2.0 * v(0, q)));
    EXPECT_DOUBLE_EQ(v(2, q), 9.80665 * v(1, q));
  }
  EXPECT_NEAR(v(0, 1), cgHeight(p, 200.0, 0.4), 1e-14);
}

// Three germs (load, position, height) with non-trivial posterior-like
// expansions: a linear function of the parameters is projected exactly, and
// the expansions' mean and std match Monte Carlo draws of the function.
struct ThreeGerms {
  VehicleParameters p = elevated();
  ParameterMapping mapping{*rollPlane(p),
                           {kMass,
                            {"added_mass_position", 0.762, 0.25, GermSpec{}},
                            {"added_mass_height", 0.40, 0.5, GermSpec{}}}};
  PolynomialBasis basis{mapping.germs(), 3};
  Eigen::MatrixXd coefficients() const {
    Eigen::MatrixXd c = mapping.priorCoefficients(basis);
    // Mix the germs and add curvature, as a posterior has.
    for (Eigen::Index j = 4; j < c.cols(); ++j) c.col(j) = 0.2 * c.col(1 + j % 3) / double(j);
    c(0, 2) = 15.0;
    c(2, 1) = -0.02;
    return c;
  }
};

TEST(RolloverQuantities, LinearFunctionsProjectExactly) {
  const ThreeGerms g;
  const Eigen::MatrixXd c = g.coefficients();
  Eigen::MatrixXd nodes;
  Eigen::VectorXd weights;
  projectionRule(g.basis, &nodes, &weights);
  const Eigen::MatrixXd theta = c * g.basis.evaluate(nodes).transpose();  // 3 x Q
  const Eigen::RowVector3d a(0.01, -3.0, 7.0);
  const Eigen::MatrixXd f = (a * theta).array() + 4.0;
  const Eigen::MatrixXd projected = projectValues(g.basis, nodes, weights, f);
  Eigen::RowVectorXd exact = a * c;
  exact(0) += 4.0;
  EXPECT_LT((projected - exact).cwiseAbs().maxCoeff(), 1e-12);
}

// The quantities' PC mean and std against 200 000 Monte Carlo draws of the
// germs (seed), each quantity evaluated at the drawn parameters.
void expectMonteCarloMoments(const ParameterMapping& mapping, const PolynomialBasis& basis,
                             const Eigen::MatrixXd& c, const DerivedExpansions& d,
                             std::uint64_t seed) {
  const int draws = 200000;
  const Eigen::MatrixXd xi = sampleGerms(basis, draws, seed);
  const Eigen::MatrixXd f =
      rolloverValues(mapping, mapping.fullParameters(c * basis.evaluate(xi).transpose()));
  const Eigen::VectorXd mc_mean = f.rowwise().mean();
  const Eigen::VectorXd mc_std =
      ((f.colwise() - mc_mean).array().square().rowwise().sum() / (draws - 1)).sqrt();
  const Eigen::VectorXd pc_mean = pcMean(d.coefficients), pc_std = pcStddev(d.coefficients);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(pc_mean[i], mc_mean[i], 4.0 * mc_std[i] / std::sqrt(double(draws))) << d.names[i];
    EXPECT_NEAR(pc_std[i], mc_std[i], 0.01 * mc_std[i]) << d.names[i];
  }
}

TEST(RolloverQuantities, MeanAndStdMatchMonteCarloDraws) {
  const ThreeGerms g;
  const Eigen::MatrixXd c = g.coefficients();
  const DerivedExpansions d = rolloverExpansions(g.mapping, g.basis, c);
  ASSERT_FALSE(d.empty());
  expectMonteCarloMoments(g.mapping, g.basis, c, d, 7);
  const Eigen::VectorXd pc_std = pcStddev(d.coefficients);
  // The load's height moves the CG: its spread is not the load's alone.
  const ParameterMapping mass_only(*rollPlane(g.p), {kMass});
  const PolynomialBasis basis1(mass_only.germs(), 3);
  const DerivedExpansions d1 =
      rolloverExpansions(mass_only, basis1, mass_only.priorCoefficients(basis1));
  EXPECT_GT(pc_std[0], 1.5 * pcStddev(d1.coefficients)[0]);
}

// Eight germs (a road-free config's load and tolerances): beyond the tensor
// rule's size, so the sparse rule (Smolyak of level order + 1) projects. A
// linear function of the parameters (degree 2 in the germs) comes out
// exactly, and the quantities' mean and std match Monte Carlo draws.
TEST(RolloverQuantities, ManyGermsOnTheSparseRule) {
  const VehicleParameters p = elevated();
  const ParameterMapping mapping(*rollPlane(p), {kMass,
                                                 {"added_mass_position", 0.762, 0.25, GermSpec{}},
                                                 {"added_mass_height", 0.40, 0.5, GermSpec{}},
                                                 {"bar_mass", 580.0, 0.03, GermSpec{}},
                                                 {"body_cg_height", 0.25, 0.2, GermSpec{}},
                                                 {"mount_height", 0.40, 0.05, GermSpec{}},
                                                 {"wheel_radius", 0.30, 0.05, GermSpec{}},
                                                 {"unsprung_mass_left", 36.26, 0.1, GermSpec{}}});
  const PolynomialBasis basis(mapping.germs(), 2);
  Eigen::MatrixXd c = mapping.priorCoefficients(basis);
  for (Eigen::Index j = 9; j < c.cols(); ++j) c.col(j) = 0.1 * c.col(1 + j % 8) / double(j);
  c(0, 3) = 12.0;  // the load depends on its height's germ, as a posterior's does
  c(4, 1) = 0.01;
  Eigen::MatrixXd nodes;
  Eigen::VectorXd weights;
  projectionRule(basis, &nodes, &weights);
  ASSERT_LT(nodes.rows(), std::pow(6.0, 8));  // not the tensor rule
  const Eigen::MatrixXd theta = c * basis.evaluate(nodes).transpose();
  Eigen::RowVectorXd a = Eigen::RowVectorXd::LinSpaced(8, -2.0, 3.0);
  const Eigen::MatrixXd linear = (a * theta).array() + 1.0;
  Eigen::RowVectorXd exact = a * c;
  exact(0) += 1.0;
  EXPECT_LT((projectValues(basis, nodes, weights, linear) - exact).cwiseAbs().maxCoeff(), 1e-10);
  const DerivedExpansions d = rolloverExpansions(mapping, basis, c);
  ASSERT_FALSE(d.empty());
  expectMonteCarloMoments(mapping, basis, c, d, 3);
}

TEST(RolloverQuantities, AbsentWithoutHeights) {
  const ParameterMapping paper(*rollPlane(VehicleParameters{}), {kMass});  // mount_height 0
  EXPECT_FALSE(hasRolloverQuantities(paper));
  const PolynomialBasis basis(paper.germs(), 3);
  EXPECT_TRUE(rolloverExpansions(paper, basis, paper.priorCoefficients(basis)).empty());
  // A model without the roll plane's values has none either.
  const ScalarGrowthModel growth(0.5, 1.0);
  const ParameterMapping scalar(growth, {{"growth_rate", 0.5, 0.2, GermSpec{}}});
  EXPECT_FALSE(hasRolloverQuantities(scalar));
  // Nor does a non-finite expansion.
  const ParameterMapping heights(*rollPlane(elevated()), {kMass});
  Eigen::MatrixXd bad = heights.priorCoefficients(basis);
  bad(0, 1) = std::nan("");
  EXPECT_TRUE(rolloverExpansions(heights, basis, bad).empty());
  EXPECT_FALSE(rolloverExpansions(heights, basis, heights.priorCoefficients(basis)).empty());
}

class FlatFourWheelRoad : public ContactRoad {
 public:
  int contactCount() const override { return 4; }
  void heights(double, Eigen::Ref<Eigen::VectorXd> out) const override { out.setZero(); }
  std::vector<double> breakpoints(double, double) const override { return {}; }
};

FullCarParameters elevatedFullCar() {
  FullCarParameters p;
  p.added_mass = 250.0;
  p.body_cg_height = 0.20;
  p.added_mass_height = 0.40;
  p.mount_height = 0.40;
  p.wheel_radius = 0.30;
  p.anti_roll_bar[0] = 10000.0;
  p.anti_roll_bar[1] = 6000.0;
  return p;
}

// The rollover outputs of the full car: cg_height with the body mass, the
// load and all four unsprung masses (two per axle), track = w.
TEST(RolloverQuantities, FullCarValues) {
  const FullCarParameters p = elevatedFullCar();
  const FullCarModel model(p, std::make_shared<FlatFourWheelRoad>());
  const UncertainParameter height{"added_mass_height", 0.5, 1.0, GermSpec{}};
  const ParameterMapping mapping(model, {height});
  ASSERT_TRUE(hasRolloverQuantities(mapping));
  Eigen::MatrixXd full(p.toVector().size(), 2);
  full.col(0) = p.toVector();
  full.col(1) = p.toVector();
  full(fullCarDescription().parameters().at("added_mass_height"), 1) = 1.0;
  const Eigen::MatrixXd v = rolloverValues(mapping, full);
  for (int q = 0; q < 2; ++q) {
    const double h_m = q == 0 ? p.added_mass_height : 1.0;
    const double mu = 2.0 * (p.unsprung_mass[0] + p.unsprung_mass[1]), m = p.body_mass,
                 M = p.added_mass;
    const double h = ((m + M) * p.mount_height + m * p.body_cg_height + M * h_m +
                      mu * p.wheel_radius) /
                     (m + M + mu);
    EXPECT_NEAR(v(0, q), h, 1e-15);
    EXPECT_NEAR(v(1, q), p.track_width / (2.0 * h), 1e-14);
    EXPECT_NEAR(v(2, q), p.gravity * p.track_width / (2.0 * h), 1e-13);
  }
  EXPECT_GT(v(0, 1), v(0, 0));  // a higher load: a higher centre, a lower threshold
  EXPECT_LT(v(2, 1), v(2, 0));
  // Without heights (mount_height 0) there are none.
  FullCarParameters flat;
  const FullCarModel plain(flat, std::make_shared<FlatFourWheelRoad>());
  EXPECT_FALSE(hasRolloverQuantities(ParameterMapping(plain, {UncertainParameter{
                                                                 "added_mass", 200.0, 0.5,
                                                                 GermSpec{}}})));
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
