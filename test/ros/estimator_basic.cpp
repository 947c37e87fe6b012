// estimator_node on the config's analytic road (speed_bump.yaml, N = 10, no
// road/profile messages): t = 0 is one sampling interval before the first
// sample, so the node sees exactly estimate_offline's synthetic record.
#include "estimator_test_support.h"

namespace pc_ekf::test {
namespace {

const char* kNode = "/estimator_node";

class EstimatorBasic : public ::testing::Test {
 protected:
  void SetUp() override {
    config_ = loadConfigFile(configPath("speed_bump.yaml"));
    record_ = syntheticRecord(config_, config_.truth.seed);
    ASSERT_TRUE(input_.waitForEstimator());
    ASSERT_TRUE(waitUntil([&] { return estimates_.connected() && pdfs_.connected(); }, 20.0));
    reset();
  }

  // ~reset, then forget the prior it publishes.
  std::string reset() {
    std::string reply;
    prior_ = resetEstimator(kNode, estimates_, &reply);
    pdfs_.clear();
    return reply;
  }

  ros::NodeHandle nh_;
  EstimatorConfig config_;
  Record record_;
  VehicleInput input_{nh_, ""};
  Collector<ParameterEstimate> estimates_{nh_, "parameter_estimate"};
  Collector<ParameterEstimate> batches_{nh_, "parameter_estimate/batch"};
  Collector<ParameterPdf> pdfs_{nh_, "parameter_pdf"};
  ParameterEstimate prior_;
};

TEST_F(EstimatorBasic, OneEstimatePerSampleEqualToEstimateOffline) {
  const ros::Time origin(1000, 0);
  input_.record(record_, origin, false);
  ASSERT_TRUE(estimates_.waitForCount(record_.samples.size(), 30.0));
  const auto msgs = estimates_.messages();
  ASSERT_EQ(msgs.size(), record_.samples.size());
  for (std::size_t k = 0; k < msgs.size(); ++k) {
    EXPECT_EQ(msgs[k].header.stamp, stampAt(origin, record_.samples[k].time));
    EXPECT_EQ(msgs[k].sample_index, k + 1);
    EXPECT_EQ(msgs[k].time, record_.samples[k].time);  // the same double: t = stamp - origin
    EXPECT_EQ(msgs[k].method, "one_step");
    EXPECT_EQ(msgs[k].update_rule, "square_root");
    EXPECT_TRUE(msgs[k].healthy) << k;
  }
  // Same config, same data, same core: equal up to rounding (round-trip JSON).
  const auto offline = estimateOffline("--config " + configPath("speed_bump.yaml"));
  expectSameEstimate(msgs.back(), offline, 1e-9, "one_step");
  // Truth M = 223.26 kg, d_CG = 0.6882 m within 3 std.
  EXPECT_NEAR(msgs.back().mean[0], 223.26, 3 * msgs.back().stddev[0]);
  EXPECT_NEAR(msgs.back().mean[1], 0.68818, 3 * msgs.back().stddev[1]);
  // Multi-rate coherence (every 10th sample) available at sample 10 only.
  EXPECT_TRUE(msgs[8].coherence_disagreement.empty());
  ASSERT_EQ(msgs.back().coherence_disagreement.size(), 2u);
  EXPECT_EQ(msgs.back().coherence_decimation, 10u);
  EXPECT_LT(msgs.back().coherence_disagreement[0], 3.0);

  // node/pdf_every: 2 from the private namespace overrides the file's 1.
  ASSERT_TRUE(pdfs_.waitForCount(record_.samples.size() / 2, 10.0));
  const auto pdfs = pdfs_.messages();
  ASSERT_EQ(pdfs.size(), record_.samples.size() / 2);
  for (std::size_t i = 0; i < pdfs.size(); ++i) {
    EXPECT_EQ(pdfs[i].sample_index, 2 * (i + 1));
    EXPECT_EQ(pdfs[i].header.stamp, msgs[2 * i + 1].header.stamp);
  }
  const ParameterPdf& pdf = pdfs.back();
  ASSERT_EQ(pdf.bin_count.size(), 2u);
  EXPECT_EQ(pdf.bin_count[0], static_cast<unsigned>(config_.pdf.bins));
  double area = 0.0;
  for (std::uint32_t b = 0; b < pdf.bin_count[0]; ++b) {
    area += pdf.densities[b] * (pdf.edges[b + 1] - pdf.edges[b]);
  }
  EXPECT_NEAR(area, 1.0, 1e-9);
  // The node's cached germ draws (speed_bump.yaml: pdf.shared_draws false, so
  // parameter i draws with seed + i) give pcHistogram's numbers (estimate_offline's PDFs).
  const auto propagator = makePropagator(config_, makeModel(config_, makeRoad(config_)));
  const Eigen::MatrixXd coefficients = coefficientsOf(msgs.back());
  for (int i = 0; i < 2; ++i) {
    const Histogram h = pcHistogram(propagator->basis(), coefficients.row(i).transpose(),
                                    config_.pdf.draws, config_.pdf.bins, config_.pdf.seed + i);
    const std::size_t offset = i * (config_.pdf.bins + 1), bins = i * config_.pdf.bins;
    EXPECT_DOUBLE_EQ(pdf.edges[offset], h.edges(0)) << i;
    EXPECT_DOUBLE_EQ(pdf.edges[offset + config_.pdf.bins], h.edges(config_.pdf.bins)) << i;
    for (int b = 0; b < config_.pdf.bins; ++b) {
      EXPECT_DOUBLE_EQ(pdf.densities[bins + b], h.densities(b)) << i << " bin " << b;
    }
  }
}

TEST_F(EstimatorBasic, ResetReturnsToThePriorAndRearmsTheOrigin) {
  EXPECT_EQ(prior_.sample_index, 0u);
  ASSERT_EQ(prior_.mean.size(), 2u);
  EXPECT_NEAR(prior_.mean[0], 200.0, 1e-9);
  EXPECT_NEAR(prior_.mean[1], 0.762, 1e-12);
  EXPECT_NEAR(prior_.stddev[0], 100.0 / std::sqrt(5.0), 1e-9);  // Beta(2,2): var(xi) = 1/5

  MeasurementSeries half(record_.samples.begin(), record_.samples.begin() + 5);
  input_.record({half, {}}, ros::Time(2000, 0), false);
  ASSERT_TRUE(estimates_.waitForCount(5, 30.0));
  EXPECT_NE(estimates_.messages().back().mean[0], prior_.mean[0]);
  const std::string reply = reset();
  EXPECT_NE(reply.find("after 5 samples"), std::string::npos) << reply;
  EXPECT_EQ(prior_.sample_index, 0u);
  EXPECT_NEAR(prior_.mean[0], 200.0, 1e-9);

  // A new run from a later origin gives the same numbers as a fresh node.
  input_.record(record_, ros::Time(5000, 500000000), false);
  ASSERT_TRUE(estimates_.waitForCount(record_.samples.size(), 30.0));
  const auto msgs = estimates_.messages();
  EXPECT_EQ(msgs.front().sample_index, 1u);
  EXPECT_EQ(msgs.front().time, record_.samples.front().time);
  expectSameEstimate(msgs.back(), estimateOffline("--config " + configPath("speed_bump.yaml")),
                     1e-9, "after reset");
}

TEST_F(EstimatorBasic, EstimateBatchEqualsEsMdaOffline) {
  std_srvs::Trigger::Response response;
  ASSERT_TRUE(callTrigger(std::string(kNode) + "/estimate_batch", &response));
  EXPECT_FALSE(response.success);  // nothing since the reset
  EXPECT_NE(response.message.find("no samples"), std::string::npos) << response.message;

  input_.record(record_, ros::Time(7000, 0), false);
  ASSERT_TRUE(estimates_.waitForCount(record_.samples.size(), 30.0));
  batches_.clear();
  ASSERT_TRUE(callTrigger(std::string(kNode) + "/estimate_batch", &response));
  EXPECT_TRUE(response.success) << response.message;
  EXPECT_NE(response.message.find("es_mda"), std::string::npos) << response.message;
  EXPECT_NE(response.message.find("added_mass_position"), std::string::npos) << response.message;
  ASSERT_TRUE(batches_.waitForCount(1, 10.0));
  const ParameterEstimate batch = batches_.messages().back();
  EXPECT_EQ(batch.method, "es_mda");
  EXPECT_EQ(batch.sample_index, record_.samples.size());
  EXPECT_EQ(batch.header.stamp, stampAt(ros::Time(7000, 0), record_.samples.back().time));
  expectSameEstimate(
      batch, estimateOffline("--config " + configPath("speed_bump.yaml") + " --method es_mda"),
      1e-9, "es_mda");
  // ES-MDA is tighter than the one-step filter on the same record (docs/studies/results.md: case A).
  EXPECT_LT(batch.stddev[0], estimates_.messages().back().stddev[0]);
}

TEST_F(EstimatorBasic, DiagnosticsCountProcessedSamplesAndReportHealth) {
  DiagnosticsWatcher diagnostics(nh_);
  const std::string input = "estimator_node: input", health = "estimator_node: filter health";
  ASSERT_TRUE(
      waitUntil([&] { return !diagnostics.value(input, "samples processed").empty(); }, 10.0));
  const long before = std::stol(diagnostics.value(input, "samples processed"));
  input_.record(record_, ros::Time(9000, 0), false);
  ASSERT_TRUE(estimates_.waitForCount(record_.samples.size(), 30.0));
  EXPECT_TRUE(diagnostics.waitForValue(input, "samples processed",
                                       std::to_string(before + record_.samples.size()), 10.0));
  EXPECT_TRUE(diagnostics.waitForValue(health, "sample index", "10", 10.0));
  EXPECT_EQ(diagnostics.status(health)->level, diagnostic_msgs::DiagnosticStatus::OK);
  EXPECT_EQ(diagnostics.value(input, "road mode"), "analytic (config)");
  EXPECT_EQ(diagnostics.value(input, "time origin (stamp)"), "9000.000000000");
  EXPECT_EQ(diagnostics.status(input)->level, diagnostic_msgs::DiagnosticStatus::OK);
  const auto config = diagnostics.status("estimator_node: configuration");
  ASSERT_TRUE(config);
  EXPECT_NE(config->message.find("square_root"), std::string::npos) << config->message;
  EXPECT_FALSE(diagnostics.value(health, "last update latency (s)").empty());
}

}  // namespace
}  // namespace pc_ekf::test

int main(int argc, char** argv) {
  return pc_ekf::test::runRostests(argc, argv, "estimator_basic_tester");
}
