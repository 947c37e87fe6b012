// rostest: a full-car bag (synthesize_bag: road/heights, four suspension
// joints) -> replay_node (lossless) -> estimator_node with
// config/full_car_bump.yaml: one estimate per sample, each equal to
// estimate_offline --bag on the same bag to 1e-9, covering the truth; the
// diagnostics name the four joints; ~estimate_batch (ES-MDA) healthy.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <pc_ekf/ParameterEstimate.h>
#include <ros/ros.h>
#include <std_srvs/Trigger.h>

#include <cmath>
#include <sstream>

#include "replay_test_support.h"

namespace pc_ekf::test {
namespace {

constexpr std::size_t kSamples = 100;

std::vector<std::vector<double>> readCsvRows(const std::string& path,
                                             std::vector<std::string>* header) {
  std::istringstream text(readText(path));
  std::string line;
  std::getline(text, line);
  std::istringstream h(line);
  for (std::string name; std::getline(h, name, ',');) header->push_back(name);
  std::vector<std::vector<double>> rows;
  while (std::getline(text, line)) {
    std::vector<double> row;
    std::istringstream cells(line);
    for (std::string cell; std::getline(cells, cell, ',');) {
      try {
        row.push_back(std::stod(cell));
      } catch (const std::exception&) {
        row.push_back(std::nan(""));
      }
    }
    rows.push_back(row);
  }
  return rows;
}

TEST(ReplayFullCar, EveryEstimateEqualsEstimateOfflineOnTheBag) {
  ScratchDir scratch;
  const std::string bag = scratch.file("full_car.bag");
  RunResult r = run(scratch, PC_EKF_EXE_SYNTHESIZE_BAG,
                    "--config " + quote(config("full_car_bump.yaml")) + " --output " + quote(bag));
  ASSERT_EQ(r.status, 0) << r.err;
  r = run(scratch, PC_EKF_EXE_ESTIMATE_OFFLINE,
          "--config " + quote(config("full_car_bump.yaml")) + " --bag " + quote(bag) + " --out " +
              quote(scratch.file("offline")));
  ASSERT_EQ(r.status, 0) << r.err;
  std::vector<std::string> header;
  const auto rows = readCsvRows(scratch.file("offline/samples.csv"), &header);
  ASSERT_EQ(rows.size(), kSamples);
  const auto column = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };

  ros::NodeHandle nh;
  std::vector<ParameterEstimate> estimates;
  std::map<std::string, diagnostic_msgs::DiagnosticStatus> status;
  ros::Subscriber sub = nh.subscribe<ParameterEstimate>(
      "parameter_estimate", 100000, [&](const ParameterEstimate::ConstPtr& m) { estimates.push_back(*m); });
  ros::Subscriber diag = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 100, [&](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
        for (const auto& s : m->status) status[s.name] = s;
      });
  const auto spin = [] { ros::spinOnce(); };
  ASSERT_TRUE(ros::service::waitForService("/estimator_node/reset", 60000));
  ASSERT_TRUE(spinUntil(30.0, spin, [&] { return sub.getNumPublishers() > 0; }));
  ChildProcess replay(siblingExecutable("replay_node"),
                      {"_bag:=" + bag, "_rate:=20", "_lossless:=true"}, scratch.file("replay.out"),
                      scratch.file("replay.err"));
  ASSERT_TRUE(replay.waitFor(120.0, spin)) << "replay_node did not finish";
  ASSERT_EQ(replay.status(), 0) << replay.err();
  spinUntil(60.0, spin, [&] { return estimates.size() >= kSamples; });
  ASSERT_EQ(estimates.size(), kSamples);

  for (std::size_t k = 0; k < kSamples; ++k) {
    const ParameterEstimate& e = estimates[k];
    ASSERT_EQ(e.names.size(), 3u);
    for (std::size_t i = 0; i < 3; ++i) {
      const double mean = rows[k][column(e.names[i] + "_mean")];
      const double sd = rows[k][column(e.names[i] + "_stddev")];
      ASSERT_NEAR(e.mean[i], mean, 1e-9 * std::abs(mean)) << "sample " << k + 1 << " " << e.names[i];
      ASSERT_NEAR(e.stddev[i], sd, 1e-9 * std::abs(sd)) << "sample " << k + 1 << " " << e.names[i];
    }
  }
  const ParameterEstimate& last = estimates.back();
  const double truth_xi[3] = {0.2326, -0.3875, 0.3};
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_LT(std::abs(last.xi_mean[i] - truth_xi[i]), 3.0 * last.xi_stddev[i]) << last.names[i];
  }
  EXPECT_TRUE(last.healthy);

  std_srvs::Trigger batch;
  ASSERT_TRUE(ros::service::call("/estimator_node/estimate_batch", batch));
  EXPECT_TRUE(batch.response.success) << batch.response.message;
  EXPECT_NE(batch.response.message.find("; healthy"), std::string::npos) << batch.response.message;

  spinUntil(5.0, spin, [&] {
    for (const auto& [name, s] : status) {
      for (const auto& kv : s.values) {
        if (kv.key == "joints" && kv.value.find("rear_right_suspension") != std::string::npos) return true;
      }
    }
    return false;
  });
  bool named = false;
  for (const auto& [name, s] : status) {
    for (const auto& kv : s.values) named = named || (kv.key == "joints" && kv.value ==
        "front_left_suspension, front_right_suspension, rear_left_suspension, rear_right_suspension");
  }
  EXPECT_TRUE(named);
}

}  // namespace
}  // namespace pc_ekf::test

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "replay_full_car_tester");
  return RUN_ALL_TESTS();
}
