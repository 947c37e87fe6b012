// rostest: bag (N = 10) -> replay_node -> estimator_node -> plot_estimates
// --save. The figure must exist, be a PNG of the layout for two parameters
// (two rows plus the health row: 1100 x 750 pixels at 100 dpi) and record in
// its text chunk that it was drawn from exactly the 10 estimates this test
// itself received, the batch result and the bag's ground truth. A second run
// asking for more samples than arrive must fail, saying so, and still save.
#include <gtest/gtest.h>
#include <pc_ekf/ParameterEstimate.h>
#include <ros/ros.h>
#include <std_srvs/Trigger.h>

#include <cstdint>
#include <fstream>
#include <map>
#include <mutex>
#include <regex>
#include <string>
#include <vector>

#include "replay_test_support.h"
#include "rostest_main.h"

namespace pc_ekf::test {
namespace {

constexpr int kSamples = 10;  // config/speed_bump.yaml's sampling.samples
const char* kEstimator = "/estimator_node";

std::uint32_t bigEndian(const std::string& s, std::size_t at) {
  std::uint32_t v = 0;
  for (std::size_t i = 0; i < 4; ++i) v = (v << 8) | static_cast<unsigned char>(s.at(at + i));
  return v;
}

struct Png {
  std::uint32_t width = 0, height = 0;
  std::map<std::string, std::string> text;  // tEXt / uncompressed iTXt chunks
};

// Reads the header and the text chunks; ADD_FAILURE on anything but a PNG.
Png readPng(const std::string& path) {
  const std::string bytes = readText(path);
  Png png;
  if (bytes.size() < 33 || bytes.compare(0, 8, "\x89PNG\r\n\x1a\n") != 0) {
    ADD_FAILURE() << path << " is not a PNG (" << bytes.size() << " bytes)";
    return png;
  }
  for (std::size_t at = 8; at + 12 <= bytes.size();) {
    const std::uint32_t length = bigEndian(bytes, at);
    const std::string type = bytes.substr(at + 4, 4);
    const std::string data = bytes.substr(at + 8, length);
    if (type == "IHDR") {
      png.width = bigEndian(data, 0);
      png.height = bigEndian(data, 4);
    } else if (type == "tEXt" || type == "iTXt") {
      const std::size_t zero = data.find('\0');
      std::string value = data.substr(zero + 1);
      if (type == "iTXt") {  // flag, method, language\0, translated keyword\0, text
        const std::size_t lang_end = value.find('\0', 2);
        value = value.substr(value.find('\0', lang_end + 1) + 1);
      }
      png.text[data.substr(0, zero)] = value;
    }
    at += 12 + length;
  }
  return png;
}

// A number "key": N in plot_estimates' JSON record (-1 when absent).
long jsonNumber(const std::string& json, const std::string& key) {
  std::smatch m;
  if (!std::regex_search(json, m, std::regex("\"" + key + "\": (-?[0-9]+)"))) return -1;
  return std::stol(m[1]);
}

std::string plotScript() { return std::string(PC_EKF_SOURCE_DIR) + "/scripts/plot_estimates"; }

TEST(PlotEstimates, SavedFigureIsDrawnFromEveryEstimateOfTheRun) {
  ScratchDir scratch;
  const std::string bag = synthesizeBag(scratch, "speed_bump.yaml");
  ASSERT_FALSE(bag.empty());

  std::mutex lock;
  std::vector<ParameterEstimate> received;
  ros::NodeHandle nh;
  ros::Subscriber sub = nh.subscribe<ParameterEstimate>(
      "parameter_estimate", 1000, [&](const ParameterEstimate::ConstPtr& m) {
        std::lock_guard<std::mutex> guard(lock);
        received.push_back(*m);
      });

  const std::string png = scratch.file("estimates.png"), ready = scratch.file("ready");
  ChildProcess plot("/usr/bin/python3",
                    {plotScript(), "--save", png, "--samples", std::to_string(kSamples), "--batch",
                     "--ready", ready, "--timeout", "120"},
                    scratch.file("plot.out"), scratch.file("plot.err"));
  ASSERT_TRUE(spinUntil(60.0, [] {}, [&] { return std::filesystem::exists(ready); }))
      << "plot_estimates never connected: " << plot.err();

  ChildProcess replay(siblingExecutable("replay_node"),
                      {"_bag:=" + bag, "_rate:=0", "_lossless:=true", "__name:=replay_node"},
                      scratch.file("replay.out"), scratch.file("replay.err"));
  ASSERT_TRUE(replay.waitFor(120.0, [] {})) << "replay_node did not finish";
  ASSERT_EQ(replay.status(), 0) << replay.err();
  ASSERT_TRUE(spinUntil(30.0, [] {}, [&] {
    std::lock_guard<std::mutex> guard(lock);
    return received.size() >= static_cast<std::size_t>(kSamples);
  }));
  std_srvs::Trigger batch;
  ASSERT_TRUE(ros::service::waitForService(std::string(kEstimator) + "/estimate_batch", 20000));
  ASSERT_TRUE(ros::service::call(std::string(kEstimator) + "/estimate_batch", batch));
  ASSERT_TRUE(batch.response.success) << batch.response.message;

  ASSERT_TRUE(plot.waitFor(120.0, [] {})) << "plot_estimates did not finish: " << plot.err();
  EXPECT_EQ(plot.status(), 0) << plot.err();
  ASSERT_TRUE(std::filesystem::exists(png));
  EXPECT_GT(std::filesystem::file_size(png), 20000u);  // a drawn figure, not an empty canvas

  ros::Duration(0.3).sleep();  // nothing beyond the 10 samples may arrive
  std::lock_guard<std::mutex> guard(lock);
  ASSERT_EQ(received.size(), static_cast<std::size_t>(kSamples));
  const Png figure = readPng(png);
  EXPECT_EQ(figure.width, 1100u);
  EXPECT_EQ(figure.height, 750u);  // 2.5 in per row, rows = 2 parameters + health
  ASSERT_EQ(figure.text.count("pc_ekf"), 1u) << "no pc_ekf record in the PNG";
  const std::string record = figure.text.at("pc_ekf");
  EXPECT_EQ(jsonNumber(record, "estimates"), static_cast<long>(received.size())) << record;
  EXPECT_EQ(jsonNumber(record, "first_sample"), static_cast<long>(received.front().sample_index))
      << record;
  EXPECT_EQ(jsonNumber(record, "last_sample"), static_cast<long>(received.back().sample_index))
      << record;
  EXPECT_EQ(jsonNumber(record, "batch"), 1) << record;
  EXPECT_GE(jsonNumber(record, "truth"), 1) << record;  // the bag's ground_truth
  EXPECT_NE(plot.out().find("from 10 estimates (batch: yes"), std::string::npos) << plot.out();
}

TEST(PlotEstimates, TooFewEstimatesFailAndSayWhatArrived) {
  ScratchDir scratch;
  const std::string png = scratch.file("partial.png");
  ChildProcess plot("/usr/bin/python3",
                    {plotScript(), "--save", png, "--samples", "5", "--timeout", "3"},
                    scratch.file("plot.out"), scratch.file("plot.err"));
  ASSERT_TRUE(plot.waitFor(60.0, [] {}));
  EXPECT_EQ(plot.status(), 1);
  EXPECT_NE(plot.err().find("incomplete: wanted 5, got 0 estimates"), std::string::npos)
      << plot.err();
  EXPECT_TRUE(std::filesystem::exists(png));
  EXPECT_EQ(jsonNumber(readPng(png).text["pc_ekf"], "estimates"), 0);
}

TEST(PlotEstimates, RefusesAFileThatIsNoPng) {
  ScratchDir scratch;
  ChildProcess plot("/usr/bin/python3", {plotScript(), "--save", scratch.file("figure.pdf")},
                    scratch.file("plot.out"), scratch.file("plot.err"));
  ASSERT_TRUE(plot.waitFor(30.0, [] {}));
  EXPECT_EQ(plot.status(), 2);
  EXPECT_NE(plot.err().find("--save takes a .png file name"), std::string::npos) << plot.err();
}

}  // namespace
}  // namespace pc_ekf::test

int main(int argc, char** argv) {
  return pc_ekf::test::runRostests(argc, argv, "plot_estimates_tester");
}
