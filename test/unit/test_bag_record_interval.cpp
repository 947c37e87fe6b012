// A real record is read as recorded: its sample interval comes from its
// stamps, never from the config's sampling:, and truth: (which describes
// synthetic drives) is not read on it. A record written at 100 Hz is
// estimated with sampling: at 200 Hz and at 100 Hz, and with another truth:,
// through estimate_offline --measurements (CSV) and --bag: the JSON is the
// same byte for byte (but the wall time), road-free (vehicle_imu.yaml, its
// travel blended with the rate, whose noise is reckoned at the interval) and
// road-given (speed_bump.yaml).
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include "bag_test_support.h"

namespace pc_ekf {
namespace {

using test::quote;
using test::ScratchDir;

// `name` from config/ with sampling: at `rate` Hz over the same duration
// and, when `other_truth`, truth: changed (its seed, its xi, its road and
// its timing).
std::string variant(const ScratchDir& dir, const std::string& name, double rate,
                    bool other_truth) {
  YAML::Node root = YAML::LoadFile(test::config(name));
  const double duration = root["sampling"]["duration"].as<double>();
  root["sampling"]["samples"] = static_cast<int>(std::lround(duration * rate));
  if (other_truth) {
    YAML::Node truth = root["truth"];
    truth["seed"] = 99;
    if (truth["xi"]) {
      std::vector<double> xi = truth["xi"].as<std::vector<double>>();
      for (double& x : xi) x = 0.5 * x + 0.1;
      truth["xi"] = xi;
    }
    if (truth["road"]) truth["road"]["speed_kmh"] = 20.0;
    truth["timing"]["jitter"] = 1e-4;
  }
  const std::string path = dir.file(name + "_" + std::to_string(static_cast<int>(rate)) +
                                    (other_truth ? "_truth" : "") + ".yaml");
  std::ofstream(path) << root;
  return path;
}

// estimate_offline's JSON without its wall time.
std::string estimate(const ScratchDir& dir, const std::string& config, const std::string& input,
                     const std::string& method = "one_step") {
  const auto r = test::run(dir, PC_EKF_EXE_ESTIMATE_OFFLINE,
                           "--config " + quote(config) + " --method " + method + " " + input);
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("\"parameters\""), std::string::npos) << r.out;
  return std::regex_replace(r.out, std::regex("\"wall_time_s\": *[-0-9.eE+]+"), "");
}

// A record at 100 Hz by synthesize_bag: the bag and the same samples as CSV.
void record100Hz(const ScratchDir& dir, const std::string& config, const std::string& bag,
                 const std::string& csv) {
  const auto r = test::run(dir, PC_EKF_EXE_SYNTHESIZE_BAG,
                           "--config " + quote(config) + " --output " + quote(bag) + " --csv " +
                               quote(csv));
  ASSERT_EQ(r.status, 0) << r.err;
}

// config/`name`'s record at 100 Hz, as CSV and as bag, estimated with
// sampling: at 100 Hz, at 200 Hz and with another truth: alike; the CSV's
// path is returned.
std::string expectRecordReadAsRecorded(const ScratchDir& dir, const std::string& name) {
  const std::string at100 = variant(dir, name, 100.0, false);
  const std::string at200 = variant(dir, name, 200.0, false);
  const std::string truth = variant(dir, name, 200.0, true);
  const std::string bag = dir.file(name + ".bag"), csv = dir.file(name + ".csv");
  record100Hz(dir, at100, bag, csv);
  for (const std::string& input : {"--measurements " + quote(csv), "--bag " + quote(bag)}) {
    const std::string reference = estimate(dir, at100, input);
    EXPECT_EQ(estimate(dir, at200, input), reference) << name << " " << input;
    EXPECT_EQ(estimate(dir, truth, input), reference) << name << " " << input;
  }
  return csv;
}

TEST(RecordInterval, RoadFreeRecordIgnoresSamplingAndTruth) {
  ScratchDir dir;
  expectRecordReadAsRecorded(dir, "vehicle_imu.yaml");
  // The synthetic drive itself does read sampling: (200 Hz: other samples).
  EXPECT_NE(estimate(dir, variant(dir, "vehicle_imu.yaml", 200.0, false), ""),
            estimate(dir, variant(dir, "vehicle_imu.yaml", 100.0, false), ""));
}

TEST(RecordInterval, RoadGivenRecordIgnoresSamplingAndTruth) {
  ScratchDir dir;
  const std::string csv = expectRecordReadAsRecorded(dir, "speed_bump.yaml");
  // The EnKF's draws: enkf.seed, not truth.seed, on a record.
  const std::string input = "--measurements " + quote(csv);
  EXPECT_EQ(estimate(dir, variant(dir, "speed_bump.yaml", 200.0, true), input, "enkf"),
            estimate(dir, variant(dir, "speed_bump.yaml", 100.0, false), input, "enkf"));
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
