// estimate_offline's JSON (io/offline_output.cpp): every number reads back as
// the same double, strings survive quotes, backslashes, control characters
// and bytes that are not UTF-8, non-finite numbers are null; the output
// directory is created with its parents.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/io/offline_estimation.h"

namespace pc_ekf {
namespace {

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Doubles that 12 significant digits (the former output) do not carry.
OfflineResult trickyResult() {
  OfflineResult r;
  r.method = "one_step";
  r.update = "square_root";
  r.samples = 10;
  r.warnings = {"quote \" backslash \\ tab\t newline\n bell\x07", "not UTF-8: \xff\xfe end"};
  r.parameters.push_back({"added_mass", 223.26000000000002, 1.0 / 3.0, -0.38750000000000001,
                          std::numeric_limits<double>::denorm_min()});
  r.parameters.push_back({"added_mass_position", std::nextafter(0.688181, 1.0),
                          std::numeric_limits<double>::max(), -0.0, 1e-300});
  r.coherence.available = true;
  r.coherence.decimation = 10;
  r.coherence.disagreement = Eigen::Vector2d(2.0 / 3.0, std::nan(""));
  r.band_nested_fraction = 0.1 + 0.2;
  r.wall_seconds = std::numeric_limits<double>::infinity();
  r.integrations = 1L << 40;
  return r;
}

TEST(OfflineJson, NumbersReadBackBitForBit) {
  const OfflineResult r = trickyResult();
  const nlohmann::json j = nlohmann::json::parse(toJson(r));
  for (std::size_t i = 0; i < r.parameters.size(); ++i) {
    const ParameterSummary& p = r.parameters[i];
    const nlohmann::json& q = j.at("parameters").at(i);
    EXPECT_EQ(q.at("name").get<std::string>(), p.name);
    EXPECT_TRUE(sameBits(q.at("mean").get<double>(), p.mean)) << p.name;
    EXPECT_TRUE(sameBits(q.at("stddev").get<double>(), p.stddev)) << p.name;
    EXPECT_TRUE(sameBits(q.at("xi_mean").get<double>(), p.xi_mean)) << p.name;
    EXPECT_TRUE(sameBits(q.at("xi_stddev").get<double>(), p.xi_stddev)) << p.name;
  }
  // 223.26000000000002 is not 223.26: 12 digits would have merged them.
  EXPECT_NE(j["parameters"][0]["mean"].get<double>(), 223.26);
  EXPECT_TRUE(sameBits(j["coherence"]["disagreement"][0].get<double>(), 2.0 / 3.0));
  EXPECT_TRUE(j["coherence"]["disagreement"][1].is_null());
  EXPECT_TRUE(j["wall_time_s"].is_null());
  EXPECT_TRUE(sameBits(j["band_nested_fraction"].get<double>(), 0.1 + 0.2));
  EXPECT_EQ(j["integrations"].get<long>(), 1L << 40);
  EXPECT_EQ(j["warnings"][0].get<std::string>(), r.warnings[0]);
  EXPECT_EQ(j["warnings"][1].get<std::string>(), "not UTF-8: \xef\xbf\xbd\xef\xbf\xbd end");
  EXPECT_FALSE(j.contains("modes"));  // grid only
}

TEST(OfflineJson, KeysInTheDocumentedOrder) {
  const std::string text = toJson(trickyResult());
  std::size_t last = 0;
  for (const char* key : {"\"method\"", "\"update\"", "\"samples\"", "\"healthy\"", "\"warnings\"",
                          "\"parameters\"", "\"coherence\"", "\"nis_window_violations\"",
                          "\"band_nested_fraction\"", "\"integrations\"", "\"wall_time_s\"",
                          "\"predictive_check\"", "\"rejected_samples\"", "\"damped_updates\"",
                          "\"reopened\""}) {
    const std::size_t at = text.find(key);
    ASSERT_NE(at, std::string::npos) << key;
    EXPECT_GT(at, last) << key;
    last = at;
  }
}

TEST(OfflineJson, EstimateReadsBackAsTheComputedDouble) {
  EstimatorConfig c = loadConfigFile(std::string(PC_EKF_SOURCE_DIR) + "/config/speed_bump.yaml");
  const auto model = makeModel(c, makeRoad(c));
  const MeasurementSeries data = synthesizeFromConfig(c, *model, c.truth.seed);
  const std::string dir = (std::filesystem::temp_directory_path() /
                           ("pc_ekf_json_" + std::to_string(::getpid())) / "a" / "b")
                              .string();
  OfflineOutputs out(dir);  // parents created
  const OfflineResult r =
      runOfflineEstimation(c, data, model, EstimationMethod::kOneStep, 1, {}, nullptr, &out);
  out.finish(r);
  std::ifstream in(dir + "/result.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  ASSERT_EQ(j["parameters"].size(), r.parameters.size());
  for (std::size_t i = 0; i < r.parameters.size(); ++i) {
    EXPECT_TRUE(sameBits(j["parameters"][i]["mean"].get<double>(), r.parameters[i].mean));
    EXPECT_TRUE(sameBits(j["parameters"][i]["stddev"].get<double>(), r.parameters[i].stddev));
  }
  std::filesystem::remove_all(std::filesystem::path(dir).parent_path().parent_path());
}

TEST(OfflineJson, PredictiveCheckPerChannelSumsToItsStatistic) {
  // ES-MDA on the paper's bump: every sample reads u1, u2, v1, v2, so the
  // channels' mean normalised squared residuals times the samples add up to T.
  EstimatorConfig c = loadConfigFile(std::string(PC_EKF_SOURCE_DIR) + "/config/speed_bump.yaml");
  const auto model = makeModel(c, makeRoad(c));
  const MeasurementSeries data = synthesizeFromConfig(c, *model, c.truth.seed);
  const OfflineResult r = runOfflineEstimation(c, data, model, EstimationMethod::kEsMda, 1);
  const nlohmann::json j = nlohmann::json::parse(toJson(r));
  const nlohmann::json& channels = j["predictive_check"]["channels"];
  ASSERT_TRUE(j["predictive_check"]["available"].get<bool>());
  ASSERT_EQ(channels.size(), 4u);
  double sum = 0.0;
  for (const char* name : {"u1", "u2", "v1", "v2"}) {
    ASSERT_TRUE(channels.contains(name)) << name;
    sum += channels[name].get<double>() * static_cast<double>(data.size());
  }
  EXPECT_NEAR(sum, j["predictive_check"]["statistic"].get<double>(),
              1e-12 * j["predictive_check"]["statistic"].get<double>());
}

TEST(OfflineJson, UncreatableDirectoryIsNamed) {
  const std::string file = (std::filesystem::temp_directory_path() /
                            ("pc_ekf_json_file_" + std::to_string(::getpid())))
                               .string();
  std::ofstream(file) << "a file, not a directory\n";
  try {
    OfflineOutputs out(file + "/out");
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(file + "/out: cannot create the output directory"),
              std::string::npos)
        << e.what();
  }
  std::filesystem::remove(file);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
