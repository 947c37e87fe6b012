// The appendix system y' = a y through the generic interface: RK4 accuracy and order.
#include <gtest/gtest.h>

#include <cmath>

#include "pc_ekf/model/integrator.h"
#include "pc_ekf/model/scalar_growth_model.h"

namespace pc_ekf {
namespace {

TEST(ScalarGrowthModel, Interface) {
  const ScalarGrowthModel model(0.5, 2.0);
  const MechanicalModel& m = model;
  EXPECT_EQ(m.stateSize(), 1);
  EXPECT_EQ(m.parameterIndex("growth_rate"), 0);
  EXPECT_EQ(m.parameterIndex("initial_value"), 1);
  EXPECT_EQ(m.channelNames(), std::vector<std::string>{"y"});
  EXPECT_EQ(m.observationMatrix(), Eigen::MatrixXd::Ones(1, 1));
  EXPECT_EQ(m.nominalParameters(), Eigen::Vector2d(0.5, 2.0));
  EXPECT_EQ(m.invalidReason(Eigen::Vector2d(1.0, 1.0)), "");
  EXPECT_NE(m.invalidReason(Eigen::Vector2d(NAN, 1.0)).find("growth_rate"), std::string::npos);
}

Eigen::MatrixXd batchParams() {
  Eigen::MatrixXd p(2, 5);
  p << -2.0, -0.5, 0.0, 0.7, 1.5,  //
      1.0, 2.0, -3.0, 0.5, 1.0;
  return p;
}

Eigen::ArrayXXd run(const MechanicalModel& model, const Eigen::MatrixXd& params, double max_step) {
  const auto batch = model.prepare(params);
  Eigen::ArrayXXd y = batch->initialState();
  EXPECT_EQ(y.rows(), 1);
  EXPECT_EQ(y.cols(), params.cols());
  IntegratorSettings settings;
  settings.max_step = max_step;
  for (int k = 0; k < 10; ++k) integrate(model, *batch, 0.1 * k, 0.1 * (k + 1), y, settings);
  return y;
}

TEST(ScalarGrowthModel, MatchesExponentialOnBatch) {
  const ScalarGrowthModel model(1.0, 1.0);
  const Eigen::MatrixXd p = batchParams();
  const Eigen::ArrayXXd y = run(model, p, 1e-3);
  for (int q = 0; q < p.cols(); ++q) {
    const double exact = p(1, q) * std::exp(p(0, q));
    EXPECT_NEAR(y(0, q), exact, 1e-10 * std::abs(exact)) << "a = " << p(0, q);
  }
}

TEST(ScalarGrowthModel, FourthOrderUnderRefinement) {
  const ScalarGrowthModel model(1.0, 1.0);
  const Eigen::MatrixXd p = batchParams();
  const Eigen::ArrayXXd coarse = run(model, p, 0.05);
  const Eigen::ArrayXXd fine = run(model, p, 0.025);
  for (int q : {0, 4}) {  // a = -2 and 1.5
    const double exact = p(1, q) * std::exp(p(0, q));
    const double ratio = std::abs(coarse(0, q) - exact) / std::abs(fine(0, q) - exact);
    EXPECT_NEAR(ratio, 16.0, 1.0) << "a = " << p(0, q);
  }
}

TEST(Integrator, RejectsBackwardsAndIgnoresEmptyInterval) {
  const ScalarGrowthModel model(1.0, 1.0);
  const auto batch = model.prepare(batchParams());
  Eigen::ArrayXXd y = batch->initialState();
  const Eigen::ArrayXXd y0 = y;
  EXPECT_THROW(integrate(model, *batch, 1.0, 0.5, y, IntegratorSettings()), std::invalid_argument);
  integrate(model, *batch, 0.5, 0.5, y, IntegratorSettings());
  EXPECT_TRUE((y == y0).all());
  Eigen::ArrayXXd wrong(2, 5);
  EXPECT_THROW(integrate(model, *batch, 0.0, 0.1, wrong, IntegratorSettings()),
               std::invalid_argument);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
