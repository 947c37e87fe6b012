#include "pc_ekf/io/road_free_record_stream.h"

#include <algorithm>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <deque>
#include <exception>
#include <map>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "pc_ekf/io/config_error.h"
#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/io/offline_estimation.h"
#include "pc_ekf/io/road_free_stream.h"

namespace pc_ekf {
namespace {

// Every sample of the record, as loadRecord selects its channels.
bool readSelected(const EstimatorConfig& c, RecordStream& record,
                  const std::function<void(const Measurement&)>& take) {
  const std::vector<int> selected = channelIndices(c);
  const bool all = selected.size() >= c.model_type->channelNames().size();
  return record.read([&](Measurement& m) {
    if (all) {
      take(m);
    } else {
      take(onlyChannels(m, selected));
    }
  });
}

// The checker's verdict on the samples from `from` on (ConfigError thrown).
RoadFreeCheck checkFrom(const EstimatorConfig& c, RecordStream& record,
                        const std::vector<std::string>& inputs, std::size_t from) {
  RoadFreeChecker check(c, inputs);
  std::size_t k = 0;
  readSelected(c, record, [&](const Measurement& m) {
    if (k++ >= from) check.add(m);
  });
  return check.finish();
}

}  // namespace

// The selected samples written as they are (the doubles' bytes) to a
// temporary file, deleted when closed: reading them back costs far less than
// decoding a bag again, and holds nothing per sample in memory.
class RecordSpill {
 public:
  RecordSpill() : file_(std::tmpfile()) {
    if (file_) std::setvbuf(file_, nullptr, _IOFBF, 1 << 20);
  }
  ~RecordSpill() {
    if (file_) std::fclose(file_);
  }
  RecordSpill(const RecordSpill&) = delete;
  RecordSpill& operator=(const RecordSpill&) = delete;
  // False once a sample could not be written (or holds more than its
  // readings and variances).
  bool usable() const { return file_ && ok_; }
  void write(const Measurement& m) {
    if (!usable()) return;
    const std::uint32_t n = static_cast<std::uint32_t>(m.channels.size());
    const std::uint8_t variances = m.variances.size() != 0;
    ok_ = m.extra_covariance.size() == 0 && m.input_slopes.size() == 0 &&
          m.input_correlation.size() == 0 && m.values.size() == n &&
          (!variances || m.variances.size() == n) && put(&m.time, sizeof m.time) &&
          put(&n, sizeof n) && put(m.channels.data(), n * sizeof(int)) &&
          put(m.values.data(), n * sizeof(double)) && put(&variances, 1) &&
          (!variances || put(m.variances.data(), n * sizeof(double)));
  }
  bool rewind() { return usable() && std::fflush(file_) == 0 && std::fseek(file_, 0, SEEK_SET) == 0; }
  // The next sample (false at the end or on a read error).
  bool read(Measurement* m) {
    std::uint32_t n = 0;
    std::uint8_t variances = 0;
    if (!get(&m->time, sizeof m->time) || !get(&n, sizeof n)) return false;
    m->channels.resize(n);
    m->values.resize(n);
    if (!get(m->channels.data(), n * sizeof(int)) || !get(m->values.data(), n * sizeof(double)) ||
        !get(&variances, 1)) {
      return false;
    }
    m->variances.resize(variances ? n : 0);
    return !variances || get(m->variances.data(), n * sizeof(double));
  }

 private:
  bool put(const void* p, std::size_t size) { return size == 0 || std::fwrite(p, size, 1, file_) == 1; }
  bool get(void* p, std::size_t size) { return size == 0 || std::fread(p, size, 1, file_) == 1; }
  std::FILE* file_;
  bool ok_ = true;
};

namespace {

// The record read once on a thread, handed over in blocks of samples; at
// most kBlocks wait. Destroyed early (the run failed) it stops the reading.
class ReadAhead {
 public:
  ReadAhead(const EstimatorConfig& c, RecordStream& record)
      : thread_([this, &c, &record] { read(c, record); }) {}
  ~ReadAhead() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    changed_.notify_all();
    thread_.join();
  }
  // False (once next() gave null): the record could not be read as a stream.
  bool streamed() {
    std::lock_guard<std::mutex> lock(mutex_);
    return streamed_;
  }
  // The next block, or null at the end; throws what the reading threw.
  const std::vector<Measurement>* next() {
    std::unique_lock<std::mutex> lock(mutex_);
    if (taken_) {
      blocks_.pop_front();
      taken_ = false;
      changed_.notify_all();
    }
    changed_.wait(lock, [this] { return !blocks_.empty() || done_; });
    if (blocks_.empty()) {
      if (error_) std::rethrow_exception(error_);
      return nullptr;
    }
    taken_ = true;
    return &blocks_.front();
  }

 private:
  // Blocks grow from kFirstBlock to kBlock: the check starts on the first
  // rows while the rest are parsed (a short record was one block, read whole
  // before the check began).
  static constexpr std::size_t kFirstBlock = 256, kBlock = 4096, kBlocks = 4;
  struct Stopped {};
  void read(const EstimatorConfig& c, RecordStream& record) {
    std::vector<Measurement> block;
    std::size_t size = kFirstBlock;
    const auto hand = [&] {
      std::unique_lock<std::mutex> lock(mutex_);
      changed_.wait(lock, [this] { return blocks_.size() < kBlocks || stop_; });
      if (stop_) throw Stopped();
      blocks_.push_back(std::move(block));
      block.clear();
      changed_.notify_all();
    };
    std::exception_ptr error;
    bool streamed = false;
    try {
      streamed = readSelected(c, record, [&](const Measurement& m) {
        block.push_back(m);
        if (block.size() == size) {
          hand();
          size = std::min(2 * size, kBlock);
        }
      });
      if (!block.empty()) hand();
    } catch (const Stopped&) {
    } catch (...) {
      error = std::current_exception();
    }
    std::lock_guard<std::mutex> lock(mutex_);
    error_ = error;
    streamed_ = streamed;
    done_ = true;
    changed_.notify_all();
  }

  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<std::vector<Measurement>> blocks_;
  bool taken_ = false, done_ = false, stop_ = false, streamed_ = false;
  std::exception_ptr error_;
  std::thread thread_;  // last: starts once the rest is made
};

}  // namespace

std::optional<CheckedRoadFreeStream> checkRoadFreeStream(const EstimatorConfig& c,
                                                          RecordStream& record,
                                                          const std::string& name,
                                                          const std::function<void()>& after_read) {
  // Checked as it is read with every selected optional input; read again
  // only when the record lacks one of them (inputsFor then differs).
  const std::vector<std::string> assumed = RoadFreeStream::inputsFor(c);
  RoadFreeChecker check(c, assumed);
  ZeroConventionSum zero(c);
  std::map<int, std::size_t> last_read;  // channel -> last sample reading it
  std::size_t count = 0;
  auto spill = std::make_shared<RecordSpill>();
  {
    ReadAhead ahead(c, record);  // read on a thread of its own, checked here
    while (const std::vector<Measurement>* block = ahead.next()) {
      for (const Measurement& m : *block) {
        spill->write(m);
        zero.add(m);
        for (int ch : m.channels) last_read[ch] = count;
        check.add(m);
        ++count;
      }
    }
    if (!ahead.streamed()) return std::nullopt;
  }
  after_read();
  const std::string problem = zero.problem();
  if (!problem.empty()) throw ConfigError(name + ": " + problem);
  const auto readFrom = [&](std::size_t from) {
    return [&last_read, from](int ch) {
      const auto it = last_read.find(ch);
      return it != last_read.end() && it->second >= from;
    };
  };
  const std::vector<std::string> inputs = RoadFreeStream::inputsFor(c, readFrom(0));
  const RoadFreeCheck verdict = inputs == assumed ? check.finish() : checkFrom(c, record, inputs, 0);
  CheckedRoadFreeStream r;
  r.dropped = verdict.dropped;
  r.warning = verdict.warning;
  r.unread = RoadFreeStream::unreadMotionWarning(c, readFrom(0));
  r.samples = count - verdict.dropped;
  // runRoadFreeOneStep checks the samples kept once more, with their inputs.
  r.inputs = RoadFreeStream::inputsFor(c, readFrom(r.dropped));
  if (r.inputs != inputs) checkFrom(c, record, r.inputs, r.dropped);
  if (spill->rewind()) r.spill = std::move(spill);
  return r;
}

OfflineResult runRoadFreeOneStep(const EstimatorConfig& c, RecordStream& record,
                                 const CheckedRoadFreeStream& checked, SampleSink* samples) {
  return runRoadFreeOneStep(
      c,
      [&](const std::function<void(const Measurement&)>& take) {
        if (checked.spill) {
          RecordSpill& spill = *checked.spill;
          if (!spill.rewind()) throw std::runtime_error(c.source + ": temporary file not readable");
          Measurement m;
          for (std::size_t k = 0; k < checked.dropped + checked.samples; ++k) {
            if (!spill.read(&m)) throw std::runtime_error(c.source + ": temporary file cut short");
            if (k >= checked.dropped) take(m);
          }
          return;
        }
        // Read on a thread of its own, a few blocks ahead of the filter: the
        // reading (a bag's decoding, alignment) costs no time of the run's.
        ReadAhead ahead(c, record);
        std::size_t k = 0;
        while (const std::vector<Measurement>* block = ahead.next()) {
          for (const Measurement& m : *block) {
            if (k++ >= checked.dropped) take(m);
          }
        }
        if (!ahead.streamed()) {
          throw std::logic_error(c.source + ": the record could not be read again");
        }
      },
      checked.samples, checked.inputs, samples, RoadFreeStream::kObservedInterval);
}

}  // namespace pc_ekf
