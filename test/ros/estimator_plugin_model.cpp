// rostest: a model from outside pc_ekf. The quarter car of
// test/plugin_example/pc_ekf_quarter_car (loaded through pluginlib from
// model.type in its YAML) in synthesize_bag, estimate_offline and
// estimator_node: a bag with road/heights (one contact) and one suspension
// joint, replayed losslessly; every estimate equals estimate_offline --bag to
// 1e-9 and covers the true sprung mass (336 kg); ~estimate_batch healthy.
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

TEST(EstimatorPluginModel, QuarterCarFromItsPackageEstimatesItsSprungMass) {
  ScratchDir scratch;
  const std::string yaml = std::string(PC_EKF_SOURCE_DIR) +
                           "/test/plugin_example/pc_ekf_quarter_car/config/quarter_car_bump.yaml";
  const std::string bag = scratch.file("quarter_car.bag");
  RunResult r = run(scratch, PC_EKF_EXE_SYNTHESIZE_BAG, "--config " + quote(yaml) + " --output " + quote(bag));
  ASSERT_EQ(r.status, 0) << r.err;
  r = run(scratch, PC_EKF_EXE_ESTIMATE_OFFLINE,
          "--config " + quote(yaml) + " --bag " + quote(bag) + " --out " + quote(scratch.file("offline")));
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
    ASSERT_EQ(e.names.size(), 1u);
    for (std::size_t i = 0; i < 1; ++i) {
      const double mean = rows[k][column(e.names[i] + "_mean")];
      const double sd = rows[k][column(e.names[i] + "_stddev")];
      ASSERT_NEAR(e.mean[i], mean, 1e-9 * std::abs(mean)) << "sample " << k + 1 << " " << e.names[i];
      ASSERT_NEAR(e.stddev[i], sd, 1e-9 * std::abs(sd)) << "sample " << k + 1 << " " << e.names[i];
    }
  }
  const ParameterEstimate& last = estimates.back();
  EXPECT_EQ(last.names[0], "sprung_mass");
  EXPECT_LT(std::abs(last.mean[0] - 336.0), 3.0 * last.stddev[0]) << last.mean[0] << " +- " << last.stddev[0];
  EXPECT_LT(last.stddev[0], 0.01 * 90.0 / std::sqrt(5.0));  // under 1 % of the prior std

  std_srvs::Trigger batch;
  ASSERT_TRUE(ros::service::call("/estimator_node/estimate_batch", batch));
  EXPECT_TRUE(batch.response.success) << batch.response.message;
  EXPECT_NE(batch.response.message.find("; healthy"), std::string::npos) << batch.response.message;

  spinUntil(5.0, spin, [&] {
    for (const auto& [name, s] : status) {
      for (const auto& kv : s.values) {
        if (kv.key == "joints" && kv.value == "quarter_suspension") return true;
      }
    }
    return false;
  });
  bool named = false;
  for (const auto& [name, s] : status) {
    for (const auto& kv : s.values) named = named || (kv.key == "joints" && kv.value == "quarter_suspension");
  }
  EXPECT_TRUE(named);
}

}  // namespace
}  // namespace pc_ekf::test

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "estimator_plugin_model_tester");
  return RUN_ALL_TESTS();
}
