// rostest: a full-car bag (synthesize_bag: road/heights, four suspension
// joints) -> replay_node (lossless) -> estimator_node with
// config/full_car_bump.yaml: one estimate per sample, each equal to
// estimate_offline --bag on the same bag to 1e-9, covering the truth; the
// diagnostics name the four joints; ~estimate_batch (ES-MDA) healthy.
#include "model_replay_support.h"

namespace pc_ekf::test {
namespace {

TEST(ReplayFullCar, EveryEstimateEqualsEstimateOfflineOnTheBag) {
  const std::string joints =
      "front_left_suspension, front_right_suspension, rear_left_suspension, rear_right_suspension";
  ModelReplay r;
  replayAgainstOffline(config("full_car_bump.yaml"), 100, joints, &r);
  ASSERT_FALSE(HasFatalFailure());
  const ParameterEstimate& last = r.estimates.back();
  ASSERT_EQ(last.names.size(), 3u);
  const double truth_xi[3] = {0.2326, -0.3875, 0.3};
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_LT(std::abs(last.xi_mean[i] - truth_xi[i]), 3.0 * last.xi_stddev[i]) << last.names[i];
  }
  EXPECT_TRUE(last.healthy);
  EXPECT_TRUE(r.batch_ok) << r.batch_reply;
  EXPECT_NE(r.batch_reply.find("; healthy"), std::string::npos) << r.batch_reply;
  EXPECT_TRUE(r.diagnostic("joints", joints));
}

}  // namespace
}  // namespace pc_ekf::test

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "replay_full_car_tester");
  return RUN_ALL_TESTS();
}
