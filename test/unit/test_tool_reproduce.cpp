// A reduced reproduction (2 seeds, 2 data sets) through reproduce.sh against
// an independent computation: estimate_offline run directly on the same
// seeds (the executable, not the library call reproduce_runs makes), and the
// summary's aggregates (means, spreads, coverage of the config's truth, xi,
// distance and std ratio to the exact posterior, flagged fractions)
// recomputed here from those runs with their textbook formulas.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace {

const std::string kSource = PC_EKF_SOURCE_DIR;
const std::string kOffline = PC_EKF_EXE_ESTIMATE_OFFLINE;
constexpr int kSeeds = 2;

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

// A fresh directory of its own: parallel runs of the test cannot collide.
std::string uniqueTempDir() {
  std::string pattern =
      (std::filesystem::temp_directory_path() / "pc_ekf_reproduce_XXXXXX").string();
  EXPECT_NE(::mkdtemp(pattern.data()), nullptr) << pattern;
  return pattern;
}

double mean(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return s / static_cast<double>(v.size());
}

double sampleStd(const std::vector<double>& v) {  // n - 1 in the denominator
  const double m = mean(v);
  double s = 0.0;
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / static_cast<double>(v.size() - 1));
}

YAML::Node offline(const std::string& config, const std::string& method, const std::string& update,
                   int seed) {
  return YAML::Load(output(kOffline + " --config " + kSource + "/config/" + config + " --method " +
                           method + " --update " + update + " --seed " + std::to_string(seed) +
                           " 2>/dev/null"));
}

TEST(Reproduce, SummaryEqualsEstimateOfflineOnTheSameSeeds) {
  const std::string out = uniqueTempDir();
  const std::string bin = kOffline.substr(0, kOffline.rfind('/'));
  ASSERT_EQ(std::system(("PC_EKF_BIN=" + bin + " bash " + kSource +
                         "/launch_free_scripts/reproduce.sh --seeds " + std::to_string(kSeeds) +
                         " --cases bump10,linear10 --no-error-vs-n --out " + out + " 2>/dev/null")
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
  std::map<std::string, YAML::Node> grids;  // the exact posterior per config and seed
  for (const Check& c : checks) {
    SCOPED_TRACE(c.dataset + " " + c.label);
    // The truth and the parameter map from the config itself.
    const YAML::Node config = YAML::LoadFile(kSource + "/config/" + c.config);
    const char* keys[2] = {"M", "d"};
    std::vector<double> means[2], stds[2], xis[2], distance[2], ratio[2];
    std::vector<double> flagged, coherence_flagged;
    for (int seed = 1; seed <= kSeeds; ++seed) {
      const YAML::Node r = offline(c.config, c.method, c.update, seed);
      const std::string grid_key = c.config + " " + std::to_string(seed);
      if (!grids.count(grid_key)) grids[grid_key] = offline(c.config, "grid", "square_root", seed);
      const YAML::Node g = grids[grid_key];
      for (int i = 0; i < 2; ++i) {
        const double nominal = config["uncertain"][i]["nominal"].as<double>();
        const double range = config["uncertain"][i]["relative_range"].as<double>();
        const double m = r["parameters"][i]["mean"].as<double>();
        const double s = r["parameters"][i]["stddev"].as<double>();
        const double gm = g["parameters"][i]["mean"].as<double>();
        const double gs = g["parameters"][i]["stddev"].as<double>();
        means[i].push_back(m);
        stds[i].push_back(s);
        xis[i].push_back((m / nominal - 1.0) / range);
        distance[i].push_back(std::abs(m - gm) / gs);
        ratio[i].push_back(s / gs);
      }
      flagged.push_back(r["healthy"].as<bool>() ? 0.0 : 1.0);
      coherence_flagged.push_back(
          r["coherence"]["flagged"].IsDefined() && r["coherence"]["flagged"].as<bool>() ? 1.0
                                                                                        : 0.0);
    }
    const YAML::Node s = summary[c.dataset][c.label];
    ASSERT_TRUE(s.IsMap());
    EXPECT_EQ(s["seeds"].as<int>(), kSeeds);
    for (int i = 0; i < 2; ++i) {
      const std::string k = keys[i];
      SCOPED_TRACE(k);
      const double nominal = config["uncertain"][i]["nominal"].as<double>();
      const double range = config["uncertain"][i]["relative_range"].as<double>();
      const double truth = nominal * (1.0 + range * config["truth"]["xi"][i].as<double>());
      std::vector<double> covered;
      for (int j = 0; j < kSeeds; ++j) {
        covered.push_back(std::abs(means[i][j] - truth) <= 2.0 * stds[i][j] ? 1.0 : 0.0);
      }
      const double m = mean(means[i]);
      EXPECT_NEAR(s[k + "_mean"].as<double>(), m, 1e-12 * std::abs(m));
      EXPECT_NEAR(s[k + "_spread"].as<double>(), sampleStd(means[i]), 1e-9 * std::abs(m));
      EXPECT_NEAR(s[k + "_reported_std"].as<double>(), mean(stds[i]), 1e-12 * mean(stds[i]));
      EXPECT_DOUBLE_EQ(s[k + "_coverage"].as<double>(), mean(covered));
      EXPECT_NEAR(s["xi" + std::to_string(i + 1) + "_mean"].as<double>(), mean(xis[i]), 1e-12);
      EXPECT_NEAR(s[k + "_posterior_distance"].as<double>(), mean(distance[i]), 1e-9);
      EXPECT_NEAR(s[k + "_std_ratio"].as<double>(), mean(ratio[i]), 1e-9);
    }
    EXPECT_DOUBLE_EQ(s["flagged"].as<double>(), mean(flagged));
    EXPECT_DOUBLE_EQ(s["coherence_flagged"].as<double>(), mean(coherence_flagged));
    // The markdown table shows the same numbers.
    char cell[64];
    std::snprintf(cell, sizeof cell, "| %s | %.3f", c.label.c_str(), mean(means[0]));
    EXPECT_NE(md.find(cell), std::string::npos) << cell;
  }
  for (const char* fig :
       {"pdfs_bump10.png", "pdfs_linear10.png", "estimate_vs_sample.png", "coherence.png"}) {
    std::ifstream f(out + "/figures/" + fig, std::ios::binary);
    EXPECT_TRUE(f.good()) << fig;
  }
  std::filesystem::remove_all(out);
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
