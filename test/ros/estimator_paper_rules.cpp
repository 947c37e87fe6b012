// estimator_node with the paper's update rule and the paper's whole-set batch
// (private parameters override speed_bump.yaml): the same numbers as
// estimate_offline --update paper and --method whole_set on the same data.
#include "estimator_test_support.h"

namespace pc_ekf::test {
namespace {

const char* kNode = "/estimator_node";

TEST(EstimatorPaperRules, OneStepAndBatchEqualEstimateOffline) {
  ros::NodeHandle nh;
  const EstimatorConfig config = loadConfigFile(configPath("speed_bump.yaml"));
  const Record record = syntheticRecord(config, config.truth.seed);
  VehicleInput input(nh, "");
  Collector<ParameterEstimate> estimates(nh, "parameter_estimate");
  Collector<ParameterEstimate> batches(nh, "parameter_estimate/batch");
  ASSERT_TRUE(input.waitForEstimator());
  ASSERT_TRUE(waitUntil([&] { return estimates.connected() && batches.connected(); }, 20.0));
  resetEstimator(kNode, estimates);

  input.record(record, ros::Time(1000, 0), false);
  ASSERT_TRUE(estimates.waitForCount(record.samples.size(), 30.0));
  const ParameterEstimate last = estimates.messages().back();
  EXPECT_EQ(last.update_rule, "paper");
  const std::string base = "--config " + configPath("speed_bump.yaml");
  expectSameEstimate(last, estimateOffline(base + " --update paper"), 1e-9, "one_step paper");
  // The rule matters: the square-root filter gives other numbers on the same data.
  const auto square_root = estimateOffline(base);
  ASSERT_EQ(square_root.size(), 2u);
  EXPECT_GT(std::abs(last.stddev[0] - square_root[0].stddev), 1e-6 * square_root[0].stddev);

  std_srvs::Trigger::Response response;
  ASSERT_TRUE(callTrigger(std::string(kNode) + "/estimate_batch", &response));
  EXPECT_TRUE(response.success) << response.message;
  EXPECT_NE(response.message.find("whole_set"), std::string::npos) << response.message;
  ASSERT_TRUE(batches.waitForCount(1, 10.0));
  const ParameterEstimate batch = batches.messages().back();
  EXPECT_EQ(batch.method, "whole_set");
  expectSameEstimate(batch, estimateOffline(base + " --method whole_set --update paper"), 1e-9,
                     "whole_set");
}

}  // namespace
}  // namespace pc_ekf::test

int main(int argc, char** argv) {
  return pc_ekf::test::runRostests(argc, argv, "estimator_paper_rules_tester");
}
