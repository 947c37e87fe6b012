// rostest: a model from outside pc_ekf. The quarter car of
// test/plugin_example/pc_ekf_quarter_car (loaded through pluginlib from
// model.type in its YAML) in synthesize_bag, estimate_offline and
// estimator_node: a bag with road/heights (one contact) and one suspension
// joint, replayed losslessly; every estimate equals estimate_offline --bag to
// 1e-9 and covers the true sprung mass (336 kg); ~estimate_batch healthy.
#include "model_replay_support.h"

namespace pc_ekf::test {
namespace {

TEST(EstimatorPluginModel, QuarterCarFromItsPackageEstimatesItsSprungMass) {
  const std::string yaml = std::string(PC_EKF_SOURCE_DIR) +
                           "/test/plugin_example/pc_ekf_quarter_car/config/quarter_car_bump.yaml";
  ModelReplay r;
  replayAgainstOffline(yaml, 100, "quarter_suspension", &r);
  ASSERT_FALSE(HasFatalFailure());
  const ParameterEstimate& last = r.estimates.back();
  ASSERT_EQ(last.names.size(), 1u);
  EXPECT_EQ(last.names[0], "sprung_mass");
  EXPECT_LT(std::abs(last.mean[0] - 336.0), 3.0 * last.stddev[0]) << last.mean[0] << " +- " << last.stddev[0];
  EXPECT_LT(last.stddev[0], 0.01 * 90.0 / std::sqrt(5.0));  // under 1 % of the prior std
  EXPECT_TRUE(r.batch_ok) << r.batch_reply;
  EXPECT_NE(r.batch_reply.find("; healthy"), std::string::npos) << r.batch_reply;
  EXPECT_TRUE(r.diagnostic("joints", "quarter_suspension"));
}

}  // namespace
}  // namespace pc_ekf::test

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "estimator_plugin_model_tester");
  return RUN_ALL_TESTS();
}
