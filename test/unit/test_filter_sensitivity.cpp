// Sensitivity of a record from the prior forecast (src/filter/prior_sensitivity.h)
// and tolerances_prune, on y' = B theta, z = y: z_j(t) = t (B theta)_j, so the
// total index of theta_i on z_j is (B_ji n_i r_i)^2 / sum_k (B_jk n_k r_k)^2 at
// every t (nominal n, relative range r, one germ each).
#include <gtest/gtest.h>

#include "linear_forced_model.h"
#include "pc_ekf/filter/prior_sensitivity.h"
#include "pc_ekf/io/record_sensitivity.h"

namespace pc_ekf {
namespace {

using testing::LinearForcedModel;

TEST(PriorSensitivity, LinearModelClosedForm) {
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(2, 2), b(2, 3), c = Eigen::MatrixXd::Identity(2, 2);
  b << 1.0, 2.0, 0.0,  // theta2 acts on nothing: index 0
      0.0, 1.0, 0.0;
  const Eigen::Vector3d nominal(1.0, 1.5, 2.0), range(0.1, 0.2, 0.3);
  auto model = std::make_shared<LinearForcedModel>(a, b, c, nominal);
  std::vector<UncertainParameter> u;
  for (int i = 0; i < 3; ++i) u.push_back({"theta" + std::to_string(i), nominal[i], range[i], GermSpec{}});
  const PolynomialBasis basis(ParameterMapping(*model, u).germs(), 2);
  const CollocationDesign design(basis, PointSequence::kGauss, 3);
  const PcPropagator prop(model, basis, design, ParameterMapping(*model, u), IntegratorSettings{0.01});
  const PriorSensitivity s = priorSensitivity(prop, {0.1, 0.2, 0.5}, {0, 1});
  ASSERT_EQ(s.channels, (std::vector<std::string>{"z0", "z1"}));
  for (int j = 0; j < 2; ++j) {
    Eigen::Vector3d share;
    for (int i = 0; i < 3; ++i) share[i] = std::pow(b(j, i) * nominal[i] * range[i], 2);
    share /= share.sum();
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(s.total(i, j), share[i], 1e-10) << "theta" << i << " on z" << j;
      EXPECT_NEAR(s.first(i, j), share[i], 1e-10);  // linear: no interactions
    }
  }
  EXPECT_EQ(s.ranking(), (std::vector<int>{1, 0, 2}));
  EXPECT_NE(sensitivityTable(s).find("theta2"), std::string::npos);
}

// tolerances_prune keeps the load and the tolerances at or above the threshold.
TEST(PriorSensitivity, PruneFixesOnlyTolerancesBelowTheThreshold) {
  EstimatorConfig c;
  c.uncertain = {{"added_mass", 200.0, 0.5, GermSpec{}},
                 {"spring_linear_left", 19357.2, 0.1, GermSpec{}},
                 {"bar_length", 1.524, 0.005, GermSpec{}}};
  c.tolerance_count = 2;
  c.truth.xi = {0.2, 0.1, -0.3};
  c.safeguards.drift = {2.0, 0.0, 0.0};
  PriorSensitivity s;
  s.parameters = {"added_mass", "spring_linear_left", "bar_length"};
  s.channels = {"u1", "v1"};
  s.total.resize(3, 2);
  s.total << 1e-4, 1e-4,  // the load is never pruned
      0.02, 0.3, 4e-3, 9e-3;
  c.tolerances_prune = 1e-2;
  std::vector<std::string> pruned;
  const EstimatorConfig out = pruneTolerances(c, s, &pruned);
  ASSERT_EQ(out.uncertain.size(), 2u);
  EXPECT_EQ(out.uncertain[1].name, "spring_linear_left");
  EXPECT_EQ(out.tolerance_count, 1);
  EXPECT_EQ(out.truth.xi, (std::vector<double>{0.2, 0.1}));
  EXPECT_EQ(out.safeguards.drift, (std::vector<double>{2.0, 0.0}));
  ASSERT_EQ(pruned.size(), 1u);
  EXPECT_NE(pruned[0].find("bar_length"), std::string::npos);
  EXPECT_NE(pruned[0].find("9.00e-03"), std::string::npos);  // its largest index, named
  c.tolerances_prune = 0.0;
  EXPECT_EQ(pruneTolerances(c, s, nullptr).uncertain.size(), 3u);  // off: nothing fixed
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
