// estimate_offline's rollover outputs (docs/tools.md): the "derived" array on
// turns.yaml (shortened), consistent with the parameters it is a function of,
// its PDFs in pdfs.csv, and no "derived" on the paper's config (no heights).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace {

const std::string kSource = PC_EKF_SOURCE_DIR;

std::string binary() {
  std::array<char, 4096> buf{};
  const ssize_t n = readlink("/proc/self/exe", buf.data(), buf.size() - 1);
  std::string self(buf.data(), n > 0 ? n : 0);
  return self.substr(0, self.rfind('/')) + "/estimate_offline";
}

std::string tempDir() {
  static std::string dir;
  if (dir.empty()) {
    char tmpl[] = "/tmp/pc_ekf_rollover_XXXXXX";
    dir = mkdtemp(tmpl);
  }
  return dir;
}

std::string runJson(const std::string& args, int* status) {
  std::string out;
  FILE* p = popen((binary() + " " + args + " 2>" + tempDir() + "/stderr.txt").c_str(), "r");
  std::array<char, 4096> buf{};
  while (fgets(buf.data(), buf.size(), p)) out += buf.data();
  const int st = pclose(p);
  *status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return out;
}

// turns.yaml on its first 3 s (150 samples).
std::string shortTurns() {
  std::ifstream in(kSource + "/config/turns.yaml");
  std::stringstream ss;
  ss << in.rdbuf();
  std::string text = ss.str();
  const std::string a = "sampling: {samples: 700, duration: 14.0}";
  const auto pos = text.find(a);
  if (pos != std::string::npos) text.replace(pos, a.size(), "sampling: {samples: 150, duration: 3.0}");
  const std::string path = tempDir() + "/turns_short.yaml";
  std::ofstream(path) << text;
  return path;
}

// turns.yaml's vehicle: m = 580, m_u = 2 x 36.26, h_P = 0.40, h_b = 0.25, r_w = 0.30.
double cgHeight(double M, double h_M) {
  return ((580.0 + M) * 0.40 + 580.0 * 0.25 + M * h_M + 2 * 36.26 * 0.30) / (580.0 + M + 72.52);
}

TEST(EstimateOfflineRollover, DerivedArrayOnTurns) {
  int status = -1;
  const std::string out_dir = tempDir() + "/out";
  const std::string text = runJson("--config " + shortTurns() + " --out " + out_dir, &status);
  ASSERT_EQ(status, 0) << text;
  const YAML::Node j = YAML::Load(text);
  // The parameters as before: five keys each.
  ASSERT_EQ(j["parameters"].size(), 3u);
  for (const auto& p : j["parameters"]) EXPECT_EQ(p.size(), 5u);
  std::map<std::string, double> param;
  for (const auto& p : j["parameters"]) param[p["name"].as<std::string>()] = p["mean"].as<double>();

  const YAML::Node d = j["derived"];
  ASSERT_TRUE(d.IsSequence());
  ASSERT_EQ(d.size(), 3u);
  const std::vector<std::string> names{"cg_height", "static_stability_factor",
                                       "rollover_threshold"};
  std::vector<std::vector<double>> coeffs;
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(d[i]["name"].as<std::string>(), names[i]);
    coeffs.push_back(d[i]["coefficients"].as<std::vector<double>>());
    ASSERT_EQ(coeffs[i].size(), 20u);  // order 3 in three germs
    double rest = 0.0;
    for (std::size_t k = 1; k < coeffs[i].size(); ++k) rest += coeffs[i][k] * coeffs[i][k];
    EXPECT_EQ(d[i]["mean"].as<double>(), coeffs[i][0]);
    EXPECT_NEAR(d[i]["stddev"].as<double>(), std::sqrt(rest), 1e-12 * coeffs[i][0]);
  }
  for (std::size_t k = 0; k < 20; ++k) EXPECT_NEAR(coeffs[2][k], 9.81 * coeffs[1][k], 1e-12);
  const double h = d[0]["mean"].as<double>(), sd = d[0]["stddev"].as<double>();
  // Inside the prior's range, and near the function at the parameters' means
  // (the function is nearly affine over the posterior).
  EXPECT_GT(h, cgHeight(100.0, 0.2));
  EXPECT_LT(h, cgHeight(300.0, 0.6));
  EXPECT_NEAR(h, cgHeight(param["added_mass"], param["added_mass_height"]), 0.3 * sd + 5e-4);
  EXPECT_NEAR(d[1]["mean"].as<double>(), 1.524 / (2.0 * h), 0.01 * 1.524 / (2.0 * h));

  // pdfs.csv: each derived quantity's histogram after the parameters', unit area.
  std::ifstream pdfs(out_dir + "/pdfs.csv");
  std::string line;
  std::map<std::string, double> area;
  std::getline(pdfs, line);
  while (std::getline(pdfs, line)) {
    std::stringstream row(line);
    std::string name, lo, hi, density;
    std::getline(row, name, ',');
    std::getline(row, lo, ',');
    std::getline(row, hi, ',');
    std::getline(row, density, ',');
    area[name] += (std::stod(hi) - std::stod(lo)) * std::stod(density);
  }
  for (const std::string& n : names) EXPECT_NEAR(area[n], 1.0, 1e-9) << n;
  EXPECT_NEAR(area["added_mass"], 1.0, 1e-9);
}

TEST(EstimateOfflineRollover, AbsentWithoutHeights) {
  int status = -1;
  const std::string text = runJson("--config " + kSource + "/config/speed_bump.yaml", &status);
  ASSERT_EQ(status, 0) << text;
  const YAML::Node j = YAML::Load(text);
  EXPECT_EQ(j["parameters"].size(), 2u);
  EXPECT_FALSE(j["derived"].IsDefined());
  EXPECT_EQ(text.find("cg_height"), std::string::npos);
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
