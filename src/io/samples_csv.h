// samples.csv (docs/tools.md), written while the run goes on: one row per
// record, numbers as printf's %.17g (they read back as the same doubles).
// The caller's thread only copies each record into a block; a thread of its
// own formats the full blocks and appends them, in order. At most a few
// blocks wait (the caller waits beyond that), so memory does not grow with
// the record and formatting overlaps the estimation.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <fstream>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "pc_ekf/io/offline_result.h"

namespace pc_ekf {

class SamplesCsv final : public SampleSink {
 public:
  // Opens (truncates) `path`. Throws std::runtime_error.
  explicit SamplesCsv(const std::string& path);
  // Stops the thread; a file not closed stays as far as it got.
  ~SamplesCsv() override;
  SamplesCsv(const SamplesCsv&) = delete;
  SamplesCsv& operator=(const SamplesCsv&) = delete;

  void begin(const SampleColumns& columns) override;
  // Throws std::runtime_error once a write has failed.
  void add(SampleRecord record) override;
  // Every row written and the file closed; without any record the header
  // alone, with `columns` when begin() was not called. Throws
  // std::runtime_error when a write failed.
  void close(const SampleColumns& columns);

 private:
  static constexpr std::size_t kBlockRows = 64, kBlocksWaiting = 4;
  using Block = std::vector<SampleRecord>;
  void hand(Block block);  // to the thread, waiting while kBlocksWaiting wait
  void loop();
  void write(const Block& block);  // on the thread
  void writeHeader(int terms);     // on the thread, or after it stopped
  void stop();

  std::string path_;
  std::ofstream out_;
  SampleColumns columns_;  // set before the first block is handed over
  bool begun_ = false, header_ = false;
  int terms_ = 0;     // coefficient columns per parameter (the header's)
  Block open_;        // the caller's, filling
  std::vector<char> buffer_;  // the thread's text, reused block after block
  std::mutex mutex_;
  std::condition_variable wake_, room_;
  std::deque<Block> waiting_;  // guarded by mutex_
  bool stopping_ = false;      // guarded by mutex_
  std::string error_;          // guarded by mutex_
  std::thread thread_;         // last: starts once the members above exist
};

}  // namespace pc_ekf
