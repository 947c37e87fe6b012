// Checkpoints off the sample callback: BackgroundWriter runs the newest job
// only, flushes and cancels as the node needs; KeptSamples copies share their
// full blocks; a snapshot writes the same file as the whole checkpoint.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "pc_ekf/filter/kept_samples.h"
#include "pc_ekf/io/background_writer.h"
#include "pc_ekf/io/checkpoint.h"

namespace pc_ekf {
namespace {

// Holds a job until released, so that the tests control what is running.
class Gate {
 public:
  void wait() {
    std::unique_lock<std::mutex> lock(mutex_);
    entered_ = true;
    changed_.notify_all();
    changed_.wait(lock, [this] { return open_; });
  }
  void waitEntered() {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [this] { return entered_; });
  }
  void open() {
    std::lock_guard<std::mutex> lock(mutex_);
    open_ = true;
    changed_.notify_all();
  }

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  bool entered_ = false, open_ = false;
};

TEST(BackgroundWriter, LatestWinsWhileAJobRuns) {
  BackgroundWriter writer;
  Gate gate;
  std::vector<int> ran;  // written by the writer's thread only until flush()
  writer.submit([&] {
    gate.wait();
    ran.push_back(0);
  });
  gate.waitEntered();
  for (int i = 1; i <= 3; ++i) writer.submit([&ran, i] { ran.push_back(i); });
  gate.open();
  writer.flush();
  EXPECT_EQ(ran, (std::vector<int>{0, 3}));
  EXPECT_EQ(writer.written(), 2u);
  EXPECT_EQ(writer.superseded(), 2u);
}

TEST(BackgroundWriter, CancelDropsTheWaitingJobAndWaitsForTheRunningOne) {
  BackgroundWriter writer;
  Gate gate;
  std::atomic<bool> first_done{false}, second_ran{false};
  writer.submit([&] {
    gate.wait();
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    first_done = true;
  });
  gate.waitEntered();
  writer.submit([&] { second_ran = true; });
  gate.open();
  writer.cancel();
  EXPECT_TRUE(first_done);  // cancel returned only after the running job
  writer.flush();
  EXPECT_FALSE(second_ran);
  EXPECT_EQ(writer.superseded(), 1u);
}

TEST(BackgroundWriter, DestructorFlushesAndErrorsAreKept) {
  std::atomic<int> ran{0};
  {
    BackgroundWriter writer;
    writer.submit([] { throw std::runtime_error("disk full"); });
    writer.flush();
    EXPECT_EQ(writer.takeErrors(), std::vector<std::string>{"disk full"});
    EXPECT_TRUE(writer.takeErrors().empty());
    EXPECT_EQ(writer.written(), 0u);
    Gate gate;
    writer.submit([&] {
      gate.wait();
      ++ran;
    });
    gate.waitEntered();
    writer.submit([&] { ++ran; });
    gate.open();
  }  // the waiting job still runs before the thread stops
  EXPECT_EQ(ran, 2);
}

Measurement sample(int i) {
  Measurement m;
  m.time = 0.001 * (i + 1);
  m.channels = {0, 3};
  m.values = Eigen::Vector2d(i / 3.0, -i / 7.0);
  return m;
}

TEST(KeptSamples, CopiesShareFullBlocksAndStayIndependent) {
  const std::size_t n = 2 * KeptSamples::kBlockSize + 5;
  KeptSamples kept;
  MeasurementSeries expected;
  for (std::size_t i = 0; i < n; ++i) {
    kept.push_back(sample(static_cast<int>(i)));
    expected.push_back(sample(static_cast<int>(i)));
  }
  const KeptSamples copy = kept;
  kept.push_back(sample(-1));  // after the copy: the copy does not see it
  ASSERT_EQ(copy.size(), n);
  ASSERT_EQ(kept.size(), n + 1);
  const MeasurementSeries s = copy.series();
  ASSERT_EQ(s.size(), n);
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_EQ(s[i].time, expected[i].time) << i;
    EXPECT_EQ(s[i].channels, expected[i].channels) << i;
    EXPECT_EQ(s[i].values, expected[i].values) << i;
  }
  EXPECT_EQ(copy.back().time, expected.back().time);
  EXPECT_EQ(kept.back().time, sample(-1).time);
  EXPECT_EQ(KeptSamples(expected).series().size(), n);
  kept.clear();
  EXPECT_TRUE(kept.empty());
  EXPECT_THROW(kept.back(), std::out_of_range);
}

std::string readText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(CheckpointSnapshot, WritesTheSameFileAsTheWholeCheckpoint) {
  Checkpoint whole;
  whole.road_mode = "analytic";
  whole.full.x = Eigen::MatrixXd::Constant(2, 3, 1.0 / 3.0);
  whole.decimated.x = whole.full.x;
  whole.full.samples = 1500;
  for (int i = 0; i < 1500; ++i) whole.batch_samples.push_back(sample(i));
  CheckpointSnapshot snapshot;
  snapshot.checkpoint = whole;
  snapshot.checkpoint.batch_samples.clear();
  snapshot.batch = KeptSamples(whole.batch_samples);

  const std::string dir = std::filesystem::temp_directory_path().string() + "/pc_ekf_snapshot_" +
                          std::to_string(::getpid());
  std::filesystem::create_directories(dir);
  writeCheckpoint(whole, dir + "/whole.ckpt");
  {
    BackgroundWriter writer;
    writer.submit([&] { writeCheckpoint(snapshot, dir + "/snapshot.ckpt"); });
  }
  const std::string a = readText(dir + "/whole.ckpt"), b = readText(dir + "/snapshot.ckpt");
  EXPECT_FALSE(a.empty());
  EXPECT_EQ(a, b);
  EXPECT_EQ(readCheckpoint(dir + "/snapshot.ckpt").batch_samples.size(), 1500u);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
