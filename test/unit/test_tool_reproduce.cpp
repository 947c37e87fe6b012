// A reduced reproduction (2 seeds, 2 data sets) through reproduce.sh: the
// summary's numbers must equal estimate_offline run directly on the same
// seeds (no separate code path computes them).
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

namespace {

const std::string kSource = PC_EKF_SOURCE_DIR;
const std::string kOffline = PC_EKF_EXE_ESTIMATE_OFFLINE;

std::string output(const std::string& cmd) {
  std::string out;
  FILE* p = popen(cmd.c_str(), "r");
  std::array<char, 4096> buf{};
  while (fgets(buf.data(), buf.size(), p)) out += buf.data();
  EXPECT_EQ(pclose(p), 0) << cmd;
  return out;
}

std::string readAll(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

TEST(Reproduce, SummaryEqualsEstimateOfflineOnTheSameSeeds) {
  const std::string out = "/tmp/pc_ekf_reproduce_test";
  const std::string bin = kOffline.substr(0, kOffline.rfind('/'));
  ASSERT_EQ(std::system(("rm -rf " + out + " && PC_EKF_BIN=" + bin + " bash " + kSource +
                         "/launch_free_scripts/reproduce.sh --seeds 2 --cases bump10,linear10 "
                         "--no-error-vs-n --out " + out + " 2>/dev/null")
                            .c_str()),
            0);
  const YAML::Node summary = YAML::LoadFile(out + "/summary.json");
  const std::string md = readAll(out + "/summary.md");
  struct Check {
    std::string dataset, config, label, method, update;
  };
  const Check checks[] = {
      {"bump10", "speed_bump.yaml", "one_step_square_root", "one_step", "square_root"},
      {"bump10", "speed_bump.yaml", "one_step_paper", "one_step", "paper"},
      {"linear10", "sine_1hz_linear.yaml", "es_mda", "es_mda", "square_root"},
      {"linear10", "sine_1hz_linear.yaml", "grid", "grid", "square_root"}};
  for (const Check& c : checks) {
    SCOPED_TRACE(c.dataset + " " + c.label);
    double mean_m = 0.0, mean_d = 0.0, covered = 0.0;
    const double truth_m = 200.0 * (1 + 0.5 * 0.2326);
    for (int seed = 1; seed <= 2; ++seed) {
      const YAML::Node r = YAML::Load(output(kOffline + " --config " + kSource + "/config/" +
                                             c.config + " --method " + c.method + " --update " +
                                             c.update + " --seed " + std::to_string(seed) +
                                             " 2>/dev/null"));
      mean_m += r["parameters"][0]["mean"].as<double>() / 2;
      mean_d += r["parameters"][1]["mean"].as<double>() / 2;
      covered += std::abs(r["parameters"][0]["mean"].as<double>() - truth_m) <=
                         2 * r["parameters"][0]["stddev"].as<double>()
                     ? 0.5
                     : 0.0;
    }
    const YAML::Node s = summary[c.dataset][c.label];
    ASSERT_TRUE(s.IsMap());
    EXPECT_EQ(s["seeds"].as<int>(), 2);
    EXPECT_NEAR(s["M_mean"].as<double>(), mean_m, 1e-9 * mean_m);
    EXPECT_NEAR(s["d_mean"].as<double>(), mean_d, 1e-9 * mean_d);
    EXPECT_DOUBLE_EQ(s["M_coverage"].as<double>(), covered);
    // The markdown table shows the same numbers.
    char cell[64];
    std::snprintf(cell, sizeof cell, "| %s | %.3f", c.label.c_str(), mean_m);
    EXPECT_NE(md.find(cell), std::string::npos) << cell;
  }
  for (const char* fig : {"pdfs_bump10.png", "pdfs_linear10.png", "estimate_vs_sample.png",
                          "coherence.png"}) {
    std::ifstream f(out + "/figures/" + fig, std::ios::binary);
    EXPECT_TRUE(f.good()) << fig;
  }
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
