// The pieces that keep updates honest: sensor noise rule, support damping,
// drift (variance growth), re-opening, and their configuration keys.
#include <gtest/gtest.h>

#include "pc_ekf/filter/measurement.h"
#include "pc_ekf/filter/prior_correction.h"
#include "pc_ekf/filter/update_safeguards.h"
#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/io/estimator_config.h"
#include "pc_ekf/pc/pc_statistics.h"

namespace pc_ekf {
namespace {

TEST(SensorNoise, FloorPlusRelativePartNeverCollapses) {
  NoiseModel n;
  n.rule = NoiseRule::kSensor;
  n.r_relative = 0.01;
  n.channel_std = Eigen::Vector4d(1e-3, 2e-3, 1e-2, 2e-2);
  Measurement m;
  m.channels = {1, 3};
  m.values = Eigen::Vector2d(0.0, 0.5);
  const Eigen::VectorXd v = n.variances(m);
  EXPECT_DOUBLE_EQ(v[0], 4e-6);                        // zero reading: the floor
  EXPECT_DOUBLE_EQ(v[1], 4e-4 + 0.005 * 0.005);        // floor^2 + (rho z)^2
  NoiseModel paper(0.01, 1e-12);
  EXPECT_DOUBLE_EQ(paper.variances(m)[0], 1e-12);      // the paper's rule collapses
  const Eigen::VectorXd stacked = n.stackedVariances({m, m});
  ASSERT_EQ(stacked.size(), 4);
  EXPECT_DOUBLE_EQ(stacked[3], v[1]);
}

TEST(SupportDamping, LargestStepThatKeepsTheMeansInside) {
  const Eigen::Vector2d lo(-1, -1), hi(1, 1);
  EXPECT_DOUBLE_EQ(supportDamping(Eigen::Vector2d(0, 0), Eigen::Vector2d(0.5, -0.5), lo, hi), 1.0);
  // 0 -> 2 would cross at 1 - 0.002 (margin 1e-3 of the width 2): gamma = 0.499.
  EXPECT_NEAR(supportDamping(Eigen::Vector2d(0, 0), Eigen::Vector2d(2, 0.1), lo, hi), 0.499, 1e-12);
  // The more binding parameter decides.
  EXPECT_NEAR(supportDamping(Eigen::Vector2d(0, 0.5), Eigen::Vector2d(2, -4.5), lo, hi),
              (-0.998 - 0.5) / -5.0, 1e-12);
  // Infinite bounds never bind; a non-finite step is refused.
  const Eigen::Vector2d inf = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  EXPECT_DOUBLE_EQ(supportDamping(Eigen::Vector2d(0, 0), Eigen::Vector2d(1e9, -1e9), -inf, inf), 1.0);
  EXPECT_DOUBLE_EQ(supportDamping(Eigen::Vector2d(0, 0), Eigen::Vector2d(NAN, 0), lo, hi), 0.0);
}

// Covariance of the rows of PC coefficients (sum over the higher terms).
Eigen::MatrixXd pcCovariance(const Eigen::MatrixXd& x) {
  const Eigen::MatrixXd a = x.rightCols(x.cols() - 1);
  return a * a.transpose();
}

TEST(Drift, IndependentIncrementVarianceGrowsByIntensitySquaredTimesDt) {
  // 3 states + 2 parameters, S = 10 terms: room for increments orthogonal to
  // every row, so only the drifting parameters' variances change.
  Eigen::MatrixXd x = Eigen::MatrixXd::Random(5, 10);
  x(4, 0) = 0.7;
  x.row(4).tail(9).setZero();  // a parameter known exactly so far
  const Eigen::MatrixXd before = pcCovariance(x);
  const Eigen::VectorXd mean_before = x.col(0);
  applyDrift(x, 3, Eigen::Vector2d(2.0, 0.1), 0.25);
  Eigen::MatrixXd expected = before;
  expected(3, 3) += 4.0 * 0.25;
  expected(4, 4) += 0.01 * 0.25;
  EXPECT_LT((pcCovariance(x) - expected).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(Eigen::VectorXd(x.col(0)), mean_before);  // means do not move
  // Repeated increments accumulate: a random walk's variance is linear in t.
  for (int k = 0; k < 3; ++k) applyDrift(x, 3, Eigen::Vector2d(2.0, 0.1), 0.25);
  expected(3, 3) += 3.0;
  expected(4, 4) += 3 * 0.0025;
  EXPECT_LT((pcCovariance(x) - expected).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(Drift, WithoutRoomTheVarianceIsMatchedByScaling) {
  Eigen::MatrixXd x = Eigen::MatrixXd::Random(4, 3);  // S - 1 = 2 < 4 rows
  const Eigen::MatrixXd before = pcCovariance(x);
  applyDrift(x, 3, Eigen::VectorXd::Constant(1, 1.0), 0.5);
  const Eigen::MatrixXd after = pcCovariance(x);
  EXPECT_NEAR(after(3, 3), before(3, 3) + 0.5, 1e-12);
  const double f = std::sqrt(after(3, 3) / before(3, 3));
  EXPECT_NEAR(after(0, 3), f * before(0, 3), 1e-12);  // correlations kept
}

TEST(Reopen, WidthAroundTheMeanOrBackToThePrior) {
  Eigen::MatrixXd prior(1, 3), theta(1, 3);
  prior << 200.0, 40.0, 0.0;
  theta << 230.0, 0.1, 0.01;
  Eigen::MatrixXd w = theta;
  reopenParameters(w, prior, {ReopenMode::kWidth, 0.5, 10});
  EXPECT_DOUBLE_EQ(w(0, 0), 230.0);
  EXPECT_DOUBLE_EQ(w(0, 1), 20.0);
  EXPECT_DOUBLE_EQ(w(0, 2), 0.0);
  Eigen::MatrixXd p = theta;
  reopenParameters(p, prior, {ReopenMode::kPrior, 0.5, 10});
  EXPECT_EQ(p, prior);
  // Widen, never narrow: a spring whose std (600.3) is above width x its
  // prior's (0.5 x 865.7) keeps its coefficients; M (std 0.1) is widened.
  Eigen::MatrixXd two(2, 3), prior2(2, 3);
  prior2 << 200.0, 40.0, 0.0, 19357.2, 0.0, 865.7;
  two << 230.0, 0.1, 0.01, 19500.0, 600.0, 18.0;
  Eigen::MatrixXd wide = two;
  reopenParameters(wide, prior2, {ReopenMode::kWidth, 0.5, 10});
  EXPECT_DOUBLE_EQ(wide(0, 1), 20.0);
  EXPECT_DOUBLE_EQ(wide(0, 2), 0.0);
  EXPECT_EQ(Eigen::VectorXd(wide.row(1).transpose()), Eigen::VectorXd(two.row(1).transpose()));
  // The same spring at std 30: widened to 0.5 x its prior, about its mean.
  two(1, 1) = 24.0;
  wide = two;
  reopenParameters(wide, prior2, {ReopenMode::kWidth, 0.5, 10});
  EXPECT_DOUBLE_EQ(wide(1, 0), 19500.0);
  EXPECT_DOUBLE_EQ(wide(1, 1), 0.0);
  EXPECT_DOUBLE_EQ(wide(1, 2), 0.5 * 865.7);
}

// The states keep their regression on the parameters and their residual
// structure, widened by the parameters' largest std factor (they were fitted
// under those parameters), while the parameter rows are exactly
// reopenParameters' result.
TEST(Reopen, StatesKeepTheirRegressionOnTheParameters) {
  Eigen::MatrixXd x(4, 6);
  x << 0.10, 1e-3, -2e-4, 5e-5, 1e-5, 8e-4,     // state u
       -0.20, 4e-4, 3e-4, -1e-5, 6e-6, -5e-4,   // state v
       230.0, 0.10, 0.01, 0.002, 0.0, 0.0,      // M
       0.69, 1e-4, 2e-4, 0.0, 3e-5, 0.0;        // d_CG
  Eigen::MatrixXd prior = Eigen::MatrixXd::Zero(2, 6);
  prior << 200.0, 40.0, 0.0, 0.0, 0.0, 0.0,
           0.762, 0.0, 0.08, 0.0, 0.0, 0.0;
  auto regression = [](const Eigen::MatrixXd& c) {  // B = C_yt C_tt^-1, residual covariance
    const Eigen::MatrixXd b = c.block(0, 2, 2, 2) * c.block(2, 2, 2, 2).inverse();
    return std::make_pair(b, Eigen::MatrixXd(c.block(0, 0, 2, 2) - b * c.block(2, 0, 2, 2)));
  };
  for (ReopenMode mode : {ReopenMode::kWidth, ReopenMode::kPrior}) {
    Eigen::MatrixXd r = x;
    reopenExtendedState(r, 2, prior, {mode, 0.5, 3});
    Eigen::MatrixXd theta = x.bottomRows(2);
    reopenParameters(theta, prior, {mode, 0.5, 3});
    EXPECT_EQ(Eigen::MatrixXd(r.bottomRows(2)), theta);
    EXPECT_EQ(Eigen::VectorXd(r.col(0).head(2)), Eigen::VectorXd(x.col(0).head(2)));
    const auto before = regression(pcCovariance(x)), after = regression(pcCovariance(r));
    EXPECT_LT((after.first - before.first).norm(), 1e-9 * before.first.norm());
    // The residual covariance grows by the square of the largest std factor.
    double grow = 1.0;
    for (int i = 2; i < 4; ++i) {
      grow = std::max(grow, r.row(i).tail(5).norm() / x.row(i).tail(5).norm());
    }
    EXPECT_GT(grow, 10.0);
    EXPECT_LT((after.second - grow * grow * before.second).norm(),
              1e-9 * grow * grow * before.second.norm());
    // The state widened with the parameters (here by far more than it was).
    EXPECT_GT(pcCovariance(r)(0, 0), 100.0 * pcCovariance(x)(0, 0));
  }
}

// A re-linearisation's working prior: exactly the asked mean and std in the
// same germs (affine, degree-1 terms only), shrunk to keep its support inside
// the prior's; a mean on the support's edge gives no working prior (zero row).
TEST(Relinearize, WorkingPriorHasTheAskedMomentsInsideThePriorSupport) {
  const EstimatorConfig c = parseConfigString(
      "uncertain:\n"
      "  - {name: added_mass, nominal: 200.0, relative_range: 0.5, germ: {family: beta, alpha: 2, beta: 2}}\n"
      "  - {name: added_mass_position, nominal: 0.762, relative_range: 0.25, germ: {family: uniform}}\n",
      "w.yaml");
  const auto prop = makePropagator(c, makeModel(c, makeRoad(c)));
  const ParameterMapping& map = prop->mapping();
  const PolynomialBasis& basis = prop->basis();
  // Inside: mean and std as asked.
  Eigen::MatrixXd w = map.workingCoefficients(basis, Eigen::Vector2d(230.0, 0.70),
                                              Eigen::Vector2d(2.0, 0.01));
  EXPECT_NEAR(pcMean(w)[0], 230.0, 1e-12);
  EXPECT_NEAR(pcMean(w)[1], 0.70, 1e-12);
  EXPECT_NEAR(pcStddev(w)[0], 2.0, 1e-12);
  EXPECT_NEAR(pcStddev(w)[1], 0.01, 1e-12);
  // Near the upper end (300 kg): beta(2,2) spans mean +- sqrt(5) std, so the
  // std is cut to keep mean + sqrt(5) std inside; uniform spans +- sqrt(3) std.
  w = map.workingCoefficients(basis, Eigen::Vector2d(295.0, 0.94), Eigen::Vector2d(10.0, 0.1));
  EXPECT_NEAR(pcStddev(w)[0], 0.999 * 5.0 / std::sqrt(5.0), 1e-9);
  EXPECT_NEAR(pcStddev(w)[1], 0.999 * (map.upperBound(1) - 0.94) / std::sqrt(3.0), 1e-9);
  const Eigen::MatrixXd xi = Eigen::MatrixXd::Random(200, 2);  // uniform germ points
  for (int q = 0; q < xi.rows(); ++q) {
    const double v = w.row(1).dot(basis.evaluate(Eigen::Vector2d(0.0, xi(q, 1))));
    EXPECT_LT(v, map.upperBound(1));
    EXPECT_GT(v, map.lowerBound(1));
  }
  // On the edge: no room, zero row.
  w = map.workingCoefficients(basis, Eigen::Vector2d(300.0, 0.70), Eigen::Vector2d(1.0, 0.01));
  EXPECT_EQ(w.row(0).norm(), 0.0);
  EXPECT_NEAR(pcStddev(w)[1], 0.01, 1e-12);
}

// Gaussian and linear: data of information D (3 parameters) give, from a
// working prior q (mean q, covariance Q), the posterior P_q = (Q^-1 + D)^-1,
// m_q = P_q (Q^-1 q + D y); from the prior (m0, P0), P = (P0^-1 + D)^-1,
// m = P (P0^-1 m0 + D y). The correction turns the first into the second,
// also when D leaves a direction unread (a ridge only the prior bounds).
// The rules the filter and the parser share: the breach names the setting.
TEST(Relinearize, RulesNameTheBrokenSetting) {
  RelinearizeSettings s;
  s.shrink = 0.01;
  s.width = 20.0;
  EXPECT_FALSE(relinearizeBreach(s).broken());  // 0.2 < 1
  s.shrink = 0.1;                               // 0.1 x 20 = 2: a restart would widen
  EXPECT_EQ(relinearizeBreach(s).setting, "width");
  s.shrink = 1.0;
  EXPECT_EQ(relinearizeBreach(s).setting, "shrink");
  s.shrink = 0.01;
  s.width = 0.0;
  EXPECT_EQ(relinearizeBreach(s).setting, "width");
  s.shrink = 0.0;  // off: any width > 0
  s.width = 1e9;
  EXPECT_FALSE(relinearizeBreach(s).broken());
}

TEST(PriorCorrection, SwapsTheWorkingPriorForThePriorInClosedForm) {
  Eigen::Matrix3d d;  // rank 2: (1, 1, 0) / sqrt(2) is unread
  const Eigen::Vector3d u(1.0, -1.0, 0.0), w(0.0, 0.0, 1.0);
  d = 40.0 * u * u.transpose() + 9.0 * w * w.transpose();
  const Eigen::Vector3d y(0.3, -0.2, 0.5);
  // Coefficient matrices (3 x 4, orthonormal terms): constant, then a square root.
  const auto coefficients = [](const Eigen::Vector3d& mean, const Eigen::Matrix3d& cov) {
    Eigen::MatrixXd c(3, 4);
    c.col(0) = mean;
    c.rightCols(3) = cov.llt().matrixL();
    return c;
  };
  const Eigen::Vector3d m0(0.0, 0.1, -0.1), q(0.25, -0.15, 0.45);
  Eigen::Matrix3d p0 = Eigen::Vector3d(4.0, 1.0, 2.0).asDiagonal();
  p0(0, 1) = p0(1, 0) = 0.5;
  const Eigen::Matrix3d qc = Eigen::Vector3d(0.09, 0.04, 0.01).asDiagonal();
  const Eigen::Matrix3d pq = (qc.inverse() + d).inverse();
  const Eigen::Vector3d mq = pq * (qc.inverse() * q + d * y);
  const Eigen::Matrix3d p = (p0.inverse() + d).inverse();
  const Eigen::Vector3d m = p * (p0.inverse() * m0 + d * y);
  Eigen::MatrixXd posterior = coefficients(mq, pq);
  ASSERT_TRUE(correctForPrior(coefficients(m0, p0), coefficients(q, qc), posterior));
  EXPECT_LT((posterior.col(0) - m).norm(), 1e-9);
  const Eigen::MatrixXd rest = posterior.rightCols(3);
  EXPECT_LT((rest * rest.transpose() - p).norm(), 1e-9);
  // Along the unread direction the prior alone speaks: far wider than q's.
  const Eigen::Vector3d v = Eigen::Vector3d(1.0, 1.0, 0.0).normalized();
  EXPECT_GT(v.dot(p * v), 10.0 * v.dot(pq * v));
  // The working prior equal to the prior: nothing changes.
  Eigen::MatrixXd same = coefficients(mq, pq);
  ASSERT_TRUE(correctForPrior(coefficients(q, qc), coefficients(q, qc), same));
  EXPECT_LT((same - coefficients(mq, pq)).norm(), 1e-9);
}

// A parameter that walked (filter.drift) since the working prior: the
// posterior is wider than q along it and its mean has moved by the walk, not
// by data. The data carry no information there, so the corrected mean there
// is the prior's; the read direction keeps the closed form.
TEST(PriorCorrection, AWalkedDirectionCarriesNoInformation) {
  const auto coefficients = [](const Eigen::Vector2d& mean, const Eigen::Matrix2d& cov) {
    Eigen::MatrixXd c(2, 3);
    c.col(0) = mean;
    c.rightCols(2) = cov.llt().matrixL();
    return c;
  };
  const Eigen::Vector2d m0(0.0, 0.0), q(0.2, 0.1);
  const Eigen::Matrix2d p0 = Eigen::Vector2d(1.0, 1.0).asDiagonal();
  const Eigen::Matrix2d qc = Eigen::Vector2d(0.04, 0.04).asDiagonal();
  // Parameter 0 read (information 100, reading 0.3); parameter 1 unread but
  // walked: variance 0.04 + 0.05, mean moved from 0.1 to 0.9.
  const Eigen::Matrix2d pq = Eigen::Vector2d(1.0 / (25.0 + 100.0), 0.09).asDiagonal();
  const Eigen::Vector2d mq(pq(0, 0) * (25.0 * q(0) + 100.0 * 0.3), 0.9);
  Eigen::MatrixXd posterior = coefficients(mq, pq);
  ASSERT_TRUE(correctForPrior(coefficients(m0, p0), coefficients(q, qc), posterior));
  const double p_read = 1.0 / (1.0 + 100.0);
  EXPECT_NEAR(posterior(0, 0), p_read * (100.0 * 0.3), 1e-12);
  EXPECT_NEAR(posterior(1, 0), 0.0, 1e-12);  // the prior's mean: the walk is no reading
  const Eigen::MatrixXd rest = posterior.rightCols(2);
  EXPECT_NEAR((rest * rest.transpose())(0, 0), p_read, 1e-12);
  EXPECT_NEAR((rest * rest.transpose())(1, 1), 1.0, 1e-12);
}

const std::string kUncertain =
    "uncertain:\n"
    "  - {name: added_mass, nominal: 200.0, relative_range: 0.5, germ: {family: beta, alpha: 2, beta: 2}}\n"
    "  - {name: added_mass_position, nominal: 0.762, relative_range: 0.25, germ: {family: uniform}}\n";

TEST(SafeguardConfig, KeysParsedAndBadValuesNamed) {
  const EstimatorConfig c = parseConfigString(kUncertain +
      "measurement: {r_rule: sensor, sensor_std: [1e-3, 1e-3, 1e-2, 1e-2]}\n"
      "filter: {support: ignore, drift: [2.0, 0.0], reopen: {mode: prior, after: 7},\n"
      "         relinearize: {shrink: 0.01, width: 20, max_restarts: 5, max_samples: 300,\n"
      "                       prior_correction: true},\n"
      "         es_mda: {alphas: [2, 2], restarts: 3, width: 1.5}}\n"
      "health: {innovation_gate: 1e-6, predictive_check: false}\n",
      "t.yaml");
  EXPECT_EQ(c.measurement.noise.rule, NoiseRule::kSensor);
  // One per model channel: the four given for u1 u2 v1 v2, the IMU channels
  // (not selected) at the largest.
  EXPECT_EQ(c.measurement.noise.channel_std,
            (Eigen::VectorXd(7) << 1e-3, 1e-3, 1e-2, 1e-2, 1e-2, 1e-2, 1e-2).finished());
  EXPECT_EQ(c.safeguards.support, SupportRule::kIgnore);
  EXPECT_EQ(c.safeguards.drift, Eigen::Vector2d(2.0, 0.0));
  EXPECT_EQ(c.safeguards.reopen.mode, ReopenMode::kPrior);
  EXPECT_EQ(c.safeguards.reopen.after, 7);
  EXPECT_DOUBLE_EQ(c.safeguards.relinearize.shrink, 0.01);
  EXPECT_DOUBLE_EQ(c.safeguards.relinearize.width, 20.0);
  EXPECT_EQ(c.safeguards.relinearize.max_restarts, 5);
  EXPECT_EQ(c.safeguards.relinearize.max_samples, 300);
  EXPECT_TRUE(c.safeguards.relinearize.prior_correction);
  EXPECT_EQ(c.es_mda.restarts, 3);
  EXPECT_DOUBLE_EQ(c.es_mda.width, 1.5);
  EXPECT_DOUBLE_EQ(c.health.innovation_gate, 1e-6);
  EXPECT_FALSE(c.health.predictive_check);
  // Defaults: the paper's rule, damping on, no drift, no re-opening, gate off.
  const EstimatorConfig d = parseConfigString(kUncertain, "d.yaml");
  EXPECT_EQ(d.measurement.noise.rule, NoiseRule::kPaper);
  EXPECT_EQ(d.safeguards.support, SupportRule::kDamp);
  EXPECT_EQ(d.safeguards.drift.size(), 0);
  EXPECT_EQ(d.safeguards.reopen.mode, ReopenMode::kOff);
  EXPECT_EQ(d.safeguards.relinearize.shrink, 0.0);
  EXPECT_FALSE(d.safeguards.relinearize.prior_correction);
  EXPECT_EQ(d.es_mda.restarts, 0);
  EXPECT_EQ(d.health.innovation_gate, 0.0);
  const std::pair<const char*, const char*> bad[] = {
      {"measurement: {r_rule: sensor}", "measurement.sensor_std"},
      {"measurement: {r_rule: sensor, sensor_std: [1e-3, 0, 1, 1]}", "measurement.sensor_std"},
      {"measurement: {r_rule: datasheet}", "measurement.r_rule"},
      {"filter: {support: clamp}", "filter.support"},
      {"filter: {drift: [1.0]}", "filter.drift"},
      {"filter: {reopen: {mode: sometimes}}", "filter.reopen.mode"},
      {"filter: {relinearize: {shrink: 1.5}}", "filter.relinearize.shrink"},
      {"filter: {relinearize: {shrink: 0.1, width: 20}}", "filter.relinearize.width"},
      {"filter: {relinearize: {shrinks: 0.1}}", "filter.relinearize.shrinks"},
      {"filter: {relinearize: {prior_correction: yes please}}", "filter.relinearize.prior_correction"},
      {"filter: {es_mda: {restarts: -1}}", "filter.es_mda.restarts"},
      {"filter: {es_mda: {width: 1.0}}", "filter.es_mda.width"},
      {"health: {innovation_gate: 0.9}", "health.innovation_gate"},
  };
  for (const auto& [yaml, key] : bad) {
    try {
      parseConfigString(kUncertain + yaml, "bad.yaml");
      ADD_FAILURE() << "accepted: " << yaml;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
