// Shared by the test_bag_* tests: a scratch directory, running the tools and
// reading estimate_offline's JSON.
#pragma once

#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string>

namespace pc_ekf::test {

// A fresh directory under the system temp dir, removed on destruction.
class ScratchDir {
 public:
  ScratchDir() {
    std::string pattern = (std::filesystem::temp_directory_path() / "pc_ekf_bag_XXXXXX").string();
    if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
    path_ = pattern;
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

struct RunResult {
  int status = -1;  // exit status
  std::string out, err;
};

inline std::string readText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

inline std::string quote(const std::string& s) { return "'" + s + "'"; }

// Runs `exe args` (args already quoted where needed) with stdout and stderr
// captured through files in `scratch`.
inline RunResult run(const ScratchDir& scratch, const std::string& exe, const std::string& args) {
  static int counter = 0;
  const std::string tag = std::to_string(counter++);
  const std::string out = scratch.file("stdout" + tag), err = scratch.file("stderr" + tag);
  const std::string cmd = quote(exe) + " " + args + " >" + quote(out) + " 2>" + quote(err);
  const int raw = std::system(cmd.c_str());
  RunResult r;
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  r.out = readText(out);
  r.err = readText(err);
  return r;
}

struct JsonParameter {
  double mean = 0.0, stddev = 0.0;
};

// "parameters" entries of estimate_offline's JSON, by name (null = NaN).
inline std::map<std::string, JsonParameter> parseParameters(const std::string& json) {
  const auto number = [](const nlohmann::json& v) {
    return v.is_null() ? std::numeric_limits<double>::quiet_NaN() : v.get<double>();
  };
  std::map<std::string, JsonParameter> out;
  const nlohmann::json doc = nlohmann::json::parse(json);  // outlives the loop
  for (const auto& p : doc.at("parameters")) {
    out[p.at("name").get<std::string>()] = {number(p.at("mean")), number(p.at("stddev"))};
  }
  return out;
}

inline std::string config(const std::string& name) {
  return std::string(PC_EKF_SOURCE_DIR) + "/config/" + name;
}

}  // namespace pc_ekf::test
