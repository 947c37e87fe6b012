// Shared by the test_bag_* tests: a scratch directory, running the tools and
// reading estimate_offline's JSON.
#pragma once

#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
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

// "parameters" entries of estimate_offline's JSON, by name.
inline std::map<std::string, JsonParameter> parseParameters(const std::string& json) {
  static const std::regex entry(
      R"re("name": "([A-Za-z0-9_]+)", "mean": ([-+0-9.eE]+|nan|inf), "stddev": ([-+0-9.eE]+|nan|inf))re");
  std::map<std::string, JsonParameter> out;
  for (auto it = std::sregex_iterator(json.begin(), json.end(), entry);
       it != std::sregex_iterator(); ++it) {
    out[(*it)[1]] = {std::stod((*it)[2]), std::stod((*it)[3])};
  }
  return out;
}

inline std::string config(const std::string& name) {
  return std::string(PC_EKF_SOURCE_DIR) + "/config/" + name;
}

}  // namespace pc_ekf::test
