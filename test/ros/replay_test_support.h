// Shared by the replay rostests: the bag must exist before replay_node opens
// it, so the gtest node synthesises it and then starts replay_node itself as
// a child process (same directory as the tools: devel/lib/pc_ekf), with the
// master of the rostest (ROS_MASTER_URI is inherited).
#pragma once

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "../unit/bag_test_support.h"

namespace pc_ekf::test {

// An executable built beside synthesize_bag (replay_node, estimator_node).
inline std::string siblingExecutable(const std::string& name) {
  return (std::filesystem::path(PC_EKF_EXE_SYNTHESIZE_BAG).parent_path() / name).string();
}

// A child process with stdout/stderr in files; killed (SIGINT, then
// SIGKILL) if still running when destroyed, so a failing test leaves nothing.
class ChildProcess {
 public:
  ChildProcess(const std::string& exe, const std::vector<std::string>& args,
               const std::string& out_file, const std::string& err_file)
      : out_file_(out_file), err_file_(err_file) {
    // Everything allocated before fork: roscpp's threads may hold malloc's lock.
    std::vector<char*> argv{const_cast<char*>(exe.c_str())};
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    pid_ = fork();
    if (pid_ < 0) throw std::runtime_error("fork failed");
    if (pid_ == 0) {
      const int out = open(out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      const int err = open(err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (out < 0 || err < 0) _exit(127);
      dup2(out, STDOUT_FILENO);
      dup2(err, STDERR_FILENO);
      execv(exe.c_str(), argv.data());
      _exit(127);
    }
  }
  ~ChildProcess() {
    if (running()) {
      kill(pid_, SIGINT);
      if (!waitFor(5.0, [] {})) {
        kill(pid_, SIGKILL);
        waitFor(5.0, [] {});
      }
    }
  }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  bool running() const { return status_ < -1; }
  // Exit status (0..255), -1 when killed by a signal; call after waitFor.
  int status() const { return status_; }
  std::string out() const { return readText(out_file_); }
  std::string err() const { return readText(err_file_); }

  // Waits up to `seconds` for the exit, calling `poll` (e.g. ros::spinOnce)
  // every few milliseconds. True when it exited.
  bool waitFor(double seconds, const std::function<void()>& poll) {
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::milliseconds(long(seconds * 1000));
    while (running()) {
      int raw = 0;
      const pid_t r = waitpid(pid_, &raw, WNOHANG);
      if (r == pid_) {
        status_ = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
        break;
      }
      if (std::chrono::steady_clock::now() >= deadline) return false;
      poll();
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return true;
  }

 private:
  pid_t pid_ = -1;
  int status_ = -2;  // -2: running
  std::string out_file_, err_file_;
};

// synthesize_bag on config/<config_name> into `scratch`: the bag's path, or ""
// after an ADD_FAILURE with the tool's stderr.
inline std::string synthesizeBag(const ScratchDir& scratch, const std::string& config_name) {
  const std::string bag = scratch.file(config_name + ".bag");
  const RunResult r = run(scratch, PC_EKF_EXE_SYNTHESIZE_BAG,
                          "--config " + quote(config(config_name)) + " --output " + quote(bag));
  if (r.status == 0) return bag;
  ADD_FAILURE() << "synthesize_bag --config " << config_name << ": " << r.err;
  return "";
}

// Runs `until` through `poll` (ros::spinOnce) until it holds or `seconds` pass.
inline bool spinUntil(double seconds, const std::function<void()>& poll,
                      const std::function<bool()>& until) {
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::milliseconds(long(seconds * 1000));
  while (!until()) {
    if (std::chrono::steady_clock::now() >= deadline) return false;
    poll();
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return true;
}

// estimate_offline's samples.csv: the header's names and the rows (non-numbers as NaN).
inline std::vector<std::vector<double>> readCsvRows(const std::string& path,
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

}  // namespace pc_ekf::test
