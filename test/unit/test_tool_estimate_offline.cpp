// estimate_offline end to end (docs/method.md §8.3): JSON on stdout, every
// method, CSV input with missing cells, exit 2 naming the line on bad input.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

namespace {

const std::string kSource = PC_EKF_SOURCE_DIR;

std::string binary() {
  std::array<char, 4096> buf{};
  const ssize_t n = readlink("/proc/self/exe", buf.data(), buf.size() - 1);
  std::string self(buf.data(), n > 0 ? n : 0);
  return self.substr(0, self.rfind('/')) + "/estimate_offline";
}

struct Outcome {
  int status = -1;
  std::string out, err;
};

std::string tempDir() {
  static std::string dir;
  if (dir.empty()) {
    char tmpl[] = "/tmp/pc_ekf_offline_XXXXXX";
    dir = mkdtemp(tmpl);
  }
  return dir;
}

Outcome run(const std::string& args) {
  const std::string err = tempDir() + "/stderr.txt";
  Outcome o;
  FILE* p = popen((binary() + " " + args + " 2>" + err).c_str(), "r");
  std::array<char, 4096> buf{};
  while (fgets(buf.data(), buf.size(), p)) o.out += buf.data();
  const int st = pclose(p);
  o.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  std::ifstream e(err);
  std::stringstream ss;
  ss << e.rdbuf();
  o.err = ss.str();
  return o;
}

std::string writeFile(const std::string& name, const std::string& text) {
  const std::string path = tempDir() + "/" + name;
  std::ofstream(path) << text;
  return path;
}

// A faster variant of the paper config for the expensive methods.
std::string fastConfig() {
  std::ifstream in(kSource + "/config/speed_bump.yaml");
  std::stringstream ss;
  ss << in.rdbuf();
  std::string text = ss.str();
  const auto replace = [&text](const std::string& a, const std::string& b) {
    const auto pos = text.find(a);
    if (pos != std::string::npos) text.replace(pos, a.size(), b);
  };
  replace("members: 200", "members: 50");
  replace("coarse_points: 101", "coarse_points: 41");
  return writeFile("fast.yaml", text);
}

void expectSchema(const Outcome& o, const std::string& method, int samples) {
  ASSERT_EQ(o.status, 0) << o.err;
  const YAML::Node j = YAML::Load(o.out);
  EXPECT_EQ(j["method"].as<std::string>(), method);
  EXPECT_EQ(j["samples"].as<int>(), samples);
  EXPECT_TRUE(j["healthy"].IsScalar());
  EXPECT_TRUE(j["warnings"].IsSequence());
  ASSERT_EQ(j["parameters"].size(), 2u);
  const double nominal[2] = {200.0, 0.762}, range[2] = {0.5, 0.25};
  const double truth_xi[2] = {0.2326, -0.3875};
  for (int i = 0; i < 2; ++i) {
    const YAML::Node p = j["parameters"][i];
    const double mean = p["mean"].as<double>(), xi = p["xi_mean"].as<double>();
    EXPECT_NEAR(mean, nominal[i] * (1 + range[i] * xi), 1e-9 * std::abs(mean));
    EXPECT_NEAR(p["stddev"].as<double>(), nominal[i] * range[i] * p["xi_stddev"].as<double>(),
                1e-9 * std::abs(mean));
    EXPECT_GT(p["stddev"].as<double>(), 0.0);
    // Ten 1 % samples pin xi to a few hundredths of the truth.
    EXPECT_NEAR(xi, truth_xi[i], 0.03) << method << " " << p["name"].as<std::string>();
  }
  EXPECT_EQ(j["parameters"][0]["name"].as<std::string>(), "added_mass");
  EXPECT_EQ(j["parameters"][1]["name"].as<std::string>(), "added_mass_position");
}

TEST(EstimateOffline, EveryMethodPrintsTheJsonContract) {
  const std::string config = fastConfig();
  for (const std::string m : {"one_step", "whole_set", "es_mda", "enkf", "grid"}) {
    SCOPED_TRACE(m);
    expectSchema(run("--config " + config + " --method " + m), m, 10);
  }
  const Outcome paper = run("--config " + config + " --update paper");
  expectSchema(paper, "one_step", 10);
  EXPECT_EQ(YAML::Load(paper.out)["update"].as<std::string>(), "paper");
}

TEST(EstimateOffline, SeedChangesTheSyntheticNoise) {
  const std::string config = kSource + "/config/speed_bump.yaml";
  const Outcome a = run("--config " + config + " --seed 3");
  const Outcome b = run("--config " + config + " --seed 3");
  const Outcome c = run("--config " + config + " --seed 4");
  ASSERT_EQ(a.status, 0);
  EXPECT_EQ(a.out.substr(0, a.out.find("wall_time")), b.out.substr(0, b.out.find("wall_time")));
  EXPECT_NE(YAML::Load(a.out)["parameters"][0]["mean"].as<double>(),
            YAML::Load(c.out)["parameters"][0]["mean"].as<double>());
}

TEST(EstimateOffline, MeasurementCsvWithMissingCells) {
  // Write the synthetic data of seed 1 as CSV, blank some cells, estimate.
  const std::string dir = tempDir() + "/out";
  const std::string config = kSource + "/config/speed_bump.yaml";
  const Outcome full = run("--config " + config + " --out " + dir);
  ASSERT_EQ(full.status, 0) << full.err;
  std::ifstream samples(dir + "/samples.csv");
  std::string header;
  std::getline(samples, header);
  EXPECT_EQ(header.rfind("index,t,added_mass_mean,added_mass_stddev,added_mass_c0", 0), 0u);
  int rows = 0;
  for (std::string line; std::getline(samples, line);) ++rows;
  EXPECT_EQ(rows, 10);
  // PDFs integrate to one.
  std::ifstream pdfs(dir + "/pdfs.csv");
  std::getline(pdfs, header);
  EXPECT_EQ(header, "parameter,bin_low,bin_high,density");
  double area = 0.0;
  for (std::string line; std::getline(pdfs, line);) {
    std::stringstream ss(line);
    std::string name, lo, hi, dens;
    std::getline(ss, name, ',');
    std::getline(ss, lo, ',');
    std::getline(ss, hi, ',');
    std::getline(ss, dens, ',');
    if (name == "added_mass") area += (std::stod(hi) - std::stod(lo)) * std::stod(dens);
  }
  EXPECT_NEAR(area, 1.0, 1e-9);

  const std::string csv = writeFile("missing.csv",
                                    "t,u1,u2,v1,v2\n"
                                    "0.3,-0.01,-0.008,,0.02\n"
                                    "0.6,nan,-0.01,0.05,0.01\n"
                                    "0.9,0.001,,,\n");
  const Outcome o = run("--config " + config + " --measurements " + csv);
  ASSERT_EQ(o.status, 0) << o.err;
  EXPECT_EQ(YAML::Load(o.out)["samples"].as<int>(), 3);
}

void expectBadCsv(const std::string& body, const std::string& needle) {
  const std::string csv = writeFile("bad.csv", body);
  const Outcome o = run("--config " + kSource + "/config/speed_bump.yaml --measurements " + csv);
  EXPECT_EQ(o.status, 2) << body;
  EXPECT_TRUE(o.out.empty());
  EXPECT_NE(o.err.find(csv), std::string::npos) << o.err;
  EXPECT_NE(o.err.find(needle), std::string::npos) << o.err;
  EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << o.err;  // one line
}

TEST(EstimateOffline, BadCsvExitsTwoNamingTheLine) {
  expectBadCsv("time,u1,u2,v1,v2\n0.3,0,0,0,0\n", "line 1: header");
  expectBadCsv("t,u1,u2,v1,v2\n0.3,0,0,0,0\n0.6,0,abc,0,0\n", "line 3: column 'u2': 'abc'");
  expectBadCsv("t,u1,u2,v1,v2\n0.3,0,0,0,0\n0.6,0,0,0,0\n0.6,0,0,0,0\n", "line 4: time 0.6");
  expectBadCsv("t,u1,u2,v1,v2\n0.3,0,0,0\n", "line 2: 4 cells");
}

TEST(EstimateOffline, BadArgumentsAndConfigExitTwo) {
  const std::string bad = writeFile("bad.yaml", "vehicle: {bar_mass: -1}\nuncertain: []\n");
  const Outcome o = run("--config " + bad);
  EXPECT_EQ(o.status, 2);
  EXPECT_NE(o.err.find("vehicle.bar_mass"), std::string::npos) << o.err;
  EXPECT_EQ(run("--config " + kSource + "/config/speed_bump.yaml --method kalman").status, 2);
  EXPECT_EQ(run("--config " + kSource + "/config/speed_bump.yaml --update joseph").status, 2);
  EXPECT_EQ(run("--config " + kSource + "/config/speed_bump.yaml --seed -4").status, 2);
  EXPECT_EQ(run("--config /nonexistent.yaml").status, 2);
  EXPECT_EQ(run("--bogus 1").status, 2);
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
