// Message conversion (src/ros/message_conversion.h): time stamps, suspension
// JointState <-> Measurement, and the core's estimates -> messages.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/ros/estimator_run_pdfs.h"
#include "pc_ekf/ros/message_conversion.h"

namespace pc_ekf {
namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

sensor_msgs::JointState jointState(std::vector<std::string> names, std::vector<double> position,
                                   std::vector<double> velocity) {
  sensor_msgs::JointState js;
  js.name = std::move(names);
  js.position = std::move(position);
  js.velocity = std::move(velocity);
  return js;
}

void expectChannels(const Measurement& m, const std::vector<int>& channels,
                    const std::vector<double>& values) {
  ASSERT_EQ(m.channels, channels);
  ASSERT_EQ(m.values.size(), static_cast<Eigen::Index>(values.size()));
  for (std::size_t i = 0; i < values.size(); ++i) EXPECT_EQ(m.values(i), values[i]) << i;
}

// ---------------------------------------------------------------- time

TEST(BagTime, SampleTimesSurviveStampingExactly) {
  const ros::Time origin(1000000000, 0);
  for (int k = 1; k <= 100; ++k) {
    const double t = k * 3.0 / 100;  // uniformSampleTimes' formula
    EXPECT_EQ(secondsSince(stampAt(origin, t), origin), t) << k;
  }
  for (int i = 0; i <= 3000; ++i) {
    const double t = static_cast<double>(i) / 1000.0;
    EXPECT_EQ(secondsSince(stampAt(origin, t), origin), t) << i;
  }
}

TEST(BagTime, NanosecondRoundingNegativeOffsetsAndRange) {
  const ros::Time origin(100, 999999999);
  const ros::Time later = stampAt(origin, 0.0000000016);  // 1.6 ns -> 2 ns
  EXPECT_EQ(later.sec, 101u);
  EXPECT_EQ(later.nsec, 1u);
  EXPECT_DOUBLE_EQ(secondsSince(stampAt(origin, -0.25), origin), -0.25);
  EXPECT_EQ(stampAt(origin, -0.25).nsec, 749999999u);
  EXPECT_THROW(stampAt(origin, -101.0), std::invalid_argument);
  EXPECT_THROW(stampAt(origin, kNaN), std::invalid_argument);

  const ros::Time t = timeFromSeconds(1.0e9 + 0.25);
  EXPECT_EQ(t.sec, 1000000000u);
  EXPECT_EQ(t.nsec, 250000000u);
  EXPECT_THROW(timeFromSeconds(-1.0), std::invalid_argument);
  EXPECT_THROW(timeFromSeconds(5.0e9), std::invalid_argument);
}

// ---------------------------------------------------------------- JointState

TEST(JointStateConversion, BothJointsGiveChannelsU1U2V1V2) {
  const auto c = measurementFromJointState(
      jointState({"left_suspension", "right_suspension"}, {0.01, -0.02}, {0.3, -0.4}), 1.5);
  EXPECT_TRUE(c.problems.empty());
  EXPECT_EQ(c.measurement.time, 1.5);
  expectChannels(c.measurement, {0, 1, 2, 3}, {0.01, -0.02, 0.3, -0.4});
}

TEST(JointStateConversion, JointOrderInTheMessageDoesNotMatter) {
  const auto c = measurementFromJointState(
      jointState({"right_suspension", "left_suspension"}, {-0.02, 0.01}, {-0.4, 0.3}), 0.0);
  EXPECT_TRUE(c.problems.empty());
  expectChannels(c.measurement, {0, 1, 2, 3}, {0.01, -0.02, 0.3, -0.4});
}

TEST(JointStateConversion, SubsetsAndNaNAreNotObservedChannels) {
  // One joint only: its u and v.
  auto c = measurementFromJointState(jointState({"right_suspension"}, {0.5}, {0.7}), 0.0);
  EXPECT_TRUE(c.problems.empty());
  expectChannels(c.measurement, {1, 3}, {0.5, 0.7});
  // Positions only (velocity array empty).
  c = measurementFromJointState(jointState({"left_suspension", "right_suspension"}, {1, 2}, {}),
                                0.0);
  EXPECT_TRUE(c.problems.empty());
  expectChannels(c.measurement, {0, 1}, {1, 2});
  // NaN marks single channels as missing.
  c = measurementFromJointState(
      jointState({"left_suspension", "right_suspension"}, {kNaN, 2}, {3, kNaN}), 0.0);
  EXPECT_TRUE(c.problems.empty());
  expectChannels(c.measurement, {1, 2}, {2, 3});
  // Nothing observed: empty, not a problem.
  c = measurementFromJointState(
      jointState({"left_suspension", "right_suspension"}, {kNaN, kNaN}, {}), 0.0);
  EXPECT_TRUE(c.problems.empty());
  EXPECT_TRUE(c.empty());
}

TEST(JointStateConversion, UnknownNamesAreReportedAndTheRestKept) {
  const auto c = measurementFromJointState(
      jointState({"steering", "left_suspension"}, {9.0, 0.1}, {9.0, 0.2}), 0.0);
  ASSERT_EQ(c.problems.size(), 1u);
  EXPECT_NE(c.problems[0].find("unknown joint name 'steering'"), std::string::npos)
      << c.problems[0];
  expectChannels(c.measurement, {0, 2}, {0.1, 0.2});
}

TEST(JointStateConversion, WrongArrayLengthsRejectThatArray) {
  const auto c = measurementFromJointState(
      jointState({"left_suspension", "right_suspension"}, {0.1}, {0.3, 0.4}), 0.0);
  ASSERT_EQ(c.problems.size(), 1u);
  EXPECT_NE(c.problems[0].find("position has 1 entries for 2 joint names"), std::string::npos)
      << c.problems[0];
  expectChannels(c.measurement, {2, 3}, {0.3, 0.4});
  const auto both = measurementFromJointState(
      jointState({"left_suspension", "right_suspension"}, {0.1, 0.2, 0.3}, {0.4}), 0.0);
  EXPECT_EQ(both.problems.size(), 2u);
  EXPECT_TRUE(both.empty());
}

TEST(JointStateConversion, InfinityAndDuplicatesAreRejected) {
  const double inf = std::numeric_limits<double>::infinity();
  auto c = measurementFromJointState(
      jointState({"left_suspension", "right_suspension"}, {inf, 0.2}, {0.3, -inf}), 0.0);
  EXPECT_EQ(c.problems.size(), 2u);
  expectChannels(c.measurement, {1, 2}, {0.2, 0.3});
  c = measurementFromJointState(
      jointState({"left_suspension", "left_suspension", "right_suspension"}, {1, 2, 3}, {}), 0.0);
  ASSERT_EQ(c.problems.size(), 1u);
  EXPECT_NE(c.problems[0].find("more than once"), std::string::npos);
  expectChannels(c.measurement, {1}, {3});
}

TEST(JointStateConversion, JointNamesAreConfigurable) {
  const SuspensionJoints joints = suspensionJoints(*rollPlaneType(), {"fl_shock", "fr_shock"});
  auto c =
      measurementFromJointState(jointState({"fr_shock", "fl_shock"}, {2, 1}, {4, 3}), 0.0, joints);
  EXPECT_TRUE(c.problems.empty());
  expectChannels(c.measurement, {0, 1, 2, 3}, {1, 2, 3, 4});
  c = measurementFromJointState(jointState({"left_suspension"}, {1}, {}), 0.0, joints);
  EXPECT_EQ(c.problems.size(), 1u);
  EXPECT_TRUE(c.empty());
}

TEST(JointStateConversion, MeasurementToJointStateAndBack) {
  Measurement m;
  m.time = 0.3;
  m.channels = {0, 3};
  m.values = Eigen::Vector2d(0.012, -0.5);
  const ros::Time stamp(5, 300000000);
  const sensor_msgs::JointState js = jointStateFromMeasurement(m, stamp);
  EXPECT_EQ(js.header.stamp, stamp);
  ASSERT_EQ(js.name, (std::vector<std::string>{"left_suspension", "right_suspension"}));
  EXPECT_EQ(js.position[0], 0.012);
  EXPECT_TRUE(std::isnan(js.position[1]));
  EXPECT_TRUE(std::isnan(js.velocity[0]));
  EXPECT_EQ(js.velocity[1], -0.5);
  const auto back = measurementFromJointState(js, 0.3);
  EXPECT_TRUE(back.problems.empty());
  expectChannels(back.measurement, {0, 3}, {0.012, -0.5});

  m.channels = {9};  // beyond the roll plane's 9 channels
  m.values = Eigen::VectorXd::Ones(1);
  EXPECT_THROW(jointStateFromMeasurement(m, stamp), std::invalid_argument);
}

// ---------------------------------------------------------------- estimates

struct OneSample {
  EstimatorConfig config;
  std::shared_ptr<const PcPropagator> propagator;
  OneStepSettings settings;
  StepResult result;
};

// One real PC-EKF update of the paper's case A on its first synthetic sample.
OneSample oneSample() {
  OneSample s;
  s.config = loadConfigFile(std::string(PC_EKF_SOURCE_DIR) + "/config/speed_bump.yaml");
  const auto model = makeModel(s.config, makeRoad(s.config));
  s.propagator = makePropagator(s.config, model);
  s.settings = makeOneStepSettings(s.config);
  OneStepFilter filter(s.propagator, s.settings);
  const MeasurementSeries data = synthesizeFromConfig(s.config, *model, 1);
  s.result = filter.process(data.front());
  return s;
}

TEST(EstimateMessage, CarriesParametersCoefficientsBasisAndHealth) {
  const OneSample s = oneSample();
  EstimateContext ctx;
  ctx.stamp = ros::Time(1000000000, 300000000);
  ctx.update_rule = "square_root";
  const ParameterEstimate msg = estimateMessage(s.result, *s.propagator, s.settings.health, ctx);

  EXPECT_EQ(msg.header.stamp, ctx.stamp);
  EXPECT_EQ(msg.sample_index, 1u);
  EXPECT_DOUBLE_EQ(msg.time, 0.3);
  EXPECT_EQ(msg.method, "one_step");
  EXPECT_EQ(msg.update_rule, "square_root");
  ASSERT_EQ(msg.names, (std::vector<std::string>{"added_mass", "added_mass_position"}));
  const double nominal[2] = {200.0, 0.762}, range[2] = {0.5, 0.25};
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(msg.mean[i], s.result.mean(i));
    EXPECT_EQ(msg.stddev[i], s.result.stddev(i));
    EXPECT_NEAR(msg.xi_mean[i], (s.result.mean(i) / nominal[i] - 1.0) / range[i], 1e-12);
    EXPECT_NEAR(msg.xi_stddev[i], s.result.stddev(i) / (nominal[i] * range[i]), 1e-12);
  }
  // Row-major parameters x terms, S = 15 for two germs at total degree 4.
  ASSERT_EQ(msg.term_count, 15u);
  ASSERT_EQ(msg.coefficients.size(), 30u);
  EXPECT_EQ(msg.coefficients[1], s.result.coefficients(0, 1));
  EXPECT_EQ(msg.coefficients[15 + 2], s.result.coefficients(1, 2));
  EXPECT_EQ(coefficientsOf(msg), s.result.coefficients);
  EXPECT_EQ(msg.coefficients[0], msg.mean[0]);  // term 0 is the mean
  // Basis: beta(2,2) germs, graded multi-indices (0,0), (1,0), (0,1), (2,0), ...
  EXPECT_EQ(msg.germ_family, (std::vector<std::string>{"beta", "beta"}));
  EXPECT_EQ(msg.germ_alpha, (std::vector<double>{2.0, 2.0}));
  EXPECT_EQ(msg.total_degree, 4u);
  ASSERT_EQ(msg.multi_indices.size(), 30u);
  EXPECT_EQ(std::vector<std::uint32_t>(msg.multi_indices.begin(), msg.multi_indices.begin() + 8),
            (std::vector<std::uint32_t>{0, 0, 1, 0, 0, 1, 2, 0}));
  EXPECT_EQ(std::vector<std::uint32_t>(msg.multi_indices.end() - 2, msg.multi_indices.end()),
            (std::vector<std::uint32_t>{0, 4}));
  // Health copied from the filter's report.
  const HealthStatus& h = s.result.health;
  EXPECT_EQ(msg.nis, h.nis);
  EXPECT_GT(msg.nis, 0.0);
  EXPECT_EQ(msg.nis_channels, 4u);
  EXPECT_EQ(msg.nis_lower, h.nis_lower);
  EXPECT_EQ(msg.nis_upper, h.nis_upper);
  EXPECT_LT(msg.nis_lower, msg.nis_upper);
  EXPECT_EQ(msg.nis_window, 10u);
  EXPECT_EQ(msg.nis_window_mean, h.nis_window_mean);
  EXPECT_EQ(msg.nis_window_outside, h.nis_window_outside);
  ASSERT_EQ(msg.mass_outside_support.size(), 2u);
  EXPECT_EQ(msg.non_finite, h.non_finite);
  EXPECT_EQ(msg.healthy, h.healthy());
  EXPECT_TRUE(msg.coherence_disagreement.empty());
  EXPECT_FALSE(msg.coherence_flagged);
}

TEST(EstimateMessage, CoherenceFlagMakesItUnhealthy) {
  const OneSample s = oneSample();
  ParameterEstimate msg = estimateMessage(s.result, *s.propagator, s.settings.health, {});
  ASSERT_TRUE(msg.healthy);
  ParameterEstimate coherent = msg;
  setCoherence(coherent, Eigen::Vector2d(0.5, 2.9), 10, 3.0);
  EXPECT_FALSE(coherent.coherence_flagged);
  EXPECT_TRUE(coherent.healthy);
  setCoherence(msg, Eigen::Vector2d(0.5, 3.1), 10, 3.0);
  EXPECT_TRUE(msg.coherence_flagged);
  EXPECT_FALSE(msg.healthy);
  EXPECT_EQ(msg.coherence_decimation, 10u);
  EXPECT_EQ(msg.coherence_disagreement, (std::vector<double>{0.5, 3.1}));
  ASSERT_FALSE(msg.warnings.empty());
  // A later health update keeps the coherence verdict.
  setHealth(msg, s.result.health, 4, s.settings.health);
  EXPECT_FALSE(msg.healthy);
  EXPECT_NE(msg.warnings.back().find("coherence"), std::string::npos);
  setCoherence(msg, Eigen::Vector2d(kNaN, 0.0), 10, 3.0);  // NaN cannot pass
  EXPECT_TRUE(msg.coherence_flagged);
}

TEST(GroundTruthMessage, TrueValuesWithZeroSpread) {
  const EstimatorConfig config =
      loadConfigFile(std::string(PC_EKF_SOURCE_DIR) + "/config/speed_bump.yaml");
  const auto model = makeModel(config, makeRoad(config));
  const ParameterMapping mapping(*model, config.uncertain);
  const PolynomialBasis basis(mapping.germs(), 4);
  const ParameterEstimate msg =
      groundTruthMessage(mapping, Eigen::Vector2d(0.2326, -0.3875), &basis, ros::Time(7, 0));
  EXPECT_EQ(msg.method, "truth");
  EXPECT_EQ(msg.header.stamp, ros::Time(7, 0));
  EXPECT_NEAR(msg.mean[0], 223.26, 1e-12);
  EXPECT_NEAR(msg.mean[1], 0.762 * (1.0 - 0.25 * 0.3875), 1e-15);
  EXPECT_EQ(msg.stddev, (std::vector<double>{0.0, 0.0}));
  EXPECT_EQ(msg.xi_mean, (std::vector<double>{0.2326, -0.3875}));
  EXPECT_EQ(msg.xi_stddev, (std::vector<double>{0.0, 0.0}));
  const Eigen::MatrixXd c = coefficientsOf(msg);
  ASSERT_EQ(c.cols(), 15);
  EXPECT_EQ(c(0, 0), msg.mean[0]);
  EXPECT_EQ(c.rightCols(14).norm(), 0.0);
  EXPECT_TRUE(msg.healthy);
  EXPECT_THROW(groundTruthMessage(mapping, Eigen::VectorXd::Zero(3), nullptr, ros::Time(1, 0)),
               std::invalid_argument);
}

// turns.yaml (heights): the derived_* fields carry cg_height, the static
// stability factor and the rollover threshold; at the prior, cg_height's mean
// is E over the load's germ of the closed form (the load's height enters
// linearly and independently: its mean suffices); speed_bump.yaml: none.
TEST(EstimateMessage, RolloverOutputsWithHeightsOnly) {
  const EstimatorConfig turns =
      loadConfigFile(std::string(PC_EKF_SOURCE_DIR) + "/config/turns.yaml");
  const auto model = makeModel(turns, makeRoad(turns));
  const ParameterMapping mapping(*model, turns.uncertain);
  const PolynomialBasis basis(mapping.germs(), 3);
  ParameterEstimate msg;
  setCoefficients(msg, mapping.priorCoefficients(basis));
  setRolloverOutputs(msg, mapping, basis, mapping.priorCoefficients(basis));
  ASSERT_EQ(msg.derived_names, (std::vector<std::string>{"cg_height", "static_stability_factor",
                                                         "rollover_threshold"}));
  ASSERT_EQ(msg.derived_mean.size(), 3u);
  ASSERT_EQ(msg.derived_stddev.size(), 3u);
  const Eigen::MatrixXd c = derivedCoefficientsOf(msg);
  ASSERT_EQ(c.cols(), basis.size());
  EXPECT_EQ(c(0, 0), msg.derived_mean[0]);
  EXPECT_NEAR(msg.derived_stddev[1], c.row(1).tail(c.cols() - 1).norm(), 1e-15);
  // E[h] over M's Beta(2, 2) germ by a 40-point Gauss rule; h_M at its mean 0.40.
  const QuadratureRule rule = basis.family(0).gaussRule(40);
  double mean = 0.0;
  for (Eigen::Index q = 0; q < rule.nodes.size(); ++q) {
    const double M = 200.0 * (1.0 + 0.5 * rule.nodes[q]), mu = 2 * 36.26;
    mean += rule.weights[q] *
            ((580.0 + M) * 0.40 + 580.0 * 0.25 + M * 0.40 + mu * 0.30) / (580.0 + M + mu);
  }
  EXPECT_NEAR(msg.derived_mean[0], mean, 1e-12);
  EXPECT_GT(msg.derived_stddev[0], 0.005);
  // rollover_threshold = g SSF term by term (the projection is linear).
  for (Eigen::Index j = 0; j < c.cols(); ++j) EXPECT_NEAR(c(2, j), 9.81 * c(1, j), 1e-12);

  const EstimatorConfig paper =
      loadConfigFile(std::string(PC_EKF_SOURCE_DIR) + "/config/speed_bump.yaml");
  const auto paper_model = makeModel(paper, makeRoad(paper));
  const ParameterMapping paper_mapping(*paper_model, paper.uncertain);
  const PolynomialBasis paper_basis(paper_mapping.germs(), 3);
  setRolloverOutputs(msg, paper_mapping, paper_basis, paper_mapping.priorCoefficients(paper_basis));
  EXPECT_TRUE(msg.derived_names.empty());
  EXPECT_TRUE(msg.derived_mean.empty());
  EXPECT_TRUE(msg.derived_coefficients.empty());
  EXPECT_EQ(derivedCoefficientsOf(msg).size(), 0);
  msg.derived_names = {"cg_height"};  // a malformed message
  EXPECT_THROW(derivedCoefficientsOf(msg), std::invalid_argument);
}

// parameter_pdf: the rollover outputs' PDFs after the parameters' (names,
// bins, values: pcHistogram with pdf.seed, as estimate_offline's pdfs.csv),
// for shared and independent draws; none without heights.
TEST(PdfMessage, DerivedQuantitiesAfterTheParameters) {
  for (const bool shared : {true, false}) {
    EstimatorConfig turns =
        loadConfigFile(std::string(PC_EKF_SOURCE_DIR) + "/config/turns.yaml");
    turns.pdf.shared_draws = shared;
    turns.pdf.draws = 2000;
    const auto model = makeModel(turns, makeRoad(turns));
    const ParameterMapping mapping(*model, turns.uncertain);
    const PolynomialBasis basis(mapping.germs(), 2);
    const Eigen::MatrixXd coefficients = mapping.priorCoefficients(basis);
    const auto sampler = makePdfSampler(turns, basis, mapping.count());
    const auto derived = derivedPdfSampler(turns, mapping, basis, sampler);
    ASSERT_TRUE(derived);
    EXPECT_EQ(derived == sampler, shared);
    ParameterEstimate estimate;
    setCoefficients(estimate, coefficients);
    setRolloverOutputs(estimate, mapping, basis, coefficients);
    PdfRequest r{coefficients, 5, ros::Time(1.0), estimate.derived_names,
                 derivedCoefficientsOf(estimate)};
    const ParameterPdf with = parameterPdf(*sampler, mapping.names(), r, derived.get());
    const ParameterPdf without = parameterPdf(*sampler, mapping.names(), r);
    const std::size_t n = mapping.names().size();
    ASSERT_EQ(with.names.size(), n + 3);
    EXPECT_EQ(std::vector<std::string>(with.names.begin(), with.names.begin() + n), mapping.names());
    EXPECT_EQ(with.names.back(), "rollover_threshold");
    // The parameters' part is the message without them, bit for bit.
    EXPECT_EQ(std::vector<double>(with.densities.begin(),
                                  with.densities.begin() + without.densities.size()),
              without.densities);
    const Histogram h = pcHistogram(basis, r.derived.row(0).transpose(), turns.pdf.draws,
                                    turns.pdf.bins, turns.pdf.seed);
    const std::size_t at = without.densities.size();
    for (Eigen::Index b = 0; b < h.densities.size(); ++b) {
      EXPECT_EQ(with.densities[at + static_cast<std::size_t>(b)], h.densities[b]);
    }
  }
  const EstimatorConfig paper =
      loadConfigFile(std::string(PC_EKF_SOURCE_DIR) + "/config/speed_bump.yaml");
  const auto paper_model = makeModel(paper, makeRoad(paper));
  const ParameterMapping paper_mapping(*paper_model, paper.uncertain);
  const PolynomialBasis paper_basis(paper_mapping.germs(), 2);
  EXPECT_FALSE(derivedPdfSampler(paper, paper_mapping, paper_basis,
                                 makePdfSampler(paper, paper_basis, paper_mapping.count())));
}

TEST(PdfMessage, ConcatenatesHistogramsWithBinCounts) {
  Histogram a, b;
  a.edges = Eigen::Vector3d(0.0, 1.0, 2.0);
  a.densities = Eigen::Vector2d(0.25, 0.75);
  b.edges = Eigen::Vector4d(5.0, 6.0, 7.0, 8.0);
  b.densities = Eigen::Vector3d(0.1, 0.2, 0.3);
  const ParameterPdf msg = pdfMessage({"p", "q"}, {a, b}, {0.0, 0.4}, 3, ros::Time(2, 0));
  EXPECT_EQ(msg.sample_index, 3u);
  EXPECT_EQ(msg.bin_count, (std::vector<std::uint32_t>{2, 3}));
  EXPECT_EQ(msg.edges, (std::vector<double>{0, 1, 2, 5, 6, 7, 8}));
  EXPECT_EQ(msg.densities, (std::vector<double>{0.25, 0.75, 0.1, 0.2, 0.3}));
  EXPECT_EQ(msg.mass_outside, (std::vector<double>{0.0, 0.4}));
  EXPECT_THROW(pdfMessage({"p"}, {a, b}, {}, 0, ros::Time()), std::invalid_argument);
  b.densities = Eigen::Vector2d(1, 2);
  EXPECT_THROW(pdfMessage({"p", "q"}, {a, b}, {}, 0, ros::Time()), std::invalid_argument);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
