#include "pc_ekf/io/road_free_record_stream.h"

#include <condition_variable>
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
  static constexpr std::size_t kBlock = 4096, kBlocks = 4;
  struct Stopped {};
  void read(const EstimatorConfig& c, RecordStream& record) {
    std::vector<Measurement> block;
    const auto hand = [&] {
      std::unique_lock<std::mutex> lock(mutex_);
      changed_.wait(lock, [this] { return blocks_.size() < kBlocks || stop_; });
      if (stop_) throw Stopped();
      blocks_.push_back(std::move(block));
      block.clear();
      changed_.notify_all();
    };
    std::exception_ptr error;
    try {
      if (!readSelected(c, record, [&](const Measurement& m) {
            block.push_back(m);
            if (block.size() == kBlock) hand();
          })) {
        throw std::logic_error(c.source + ": the record could not be read again");
      }
      if (!block.empty()) hand();
    } catch (const Stopped&) {
    } catch (...) {
      error = std::current_exception();
    }
    std::lock_guard<std::mutex> lock(mutex_);
    error_ = error;
    done_ = true;
    changed_.notify_all();
  }

  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<std::vector<Measurement>> blocks_;
  bool taken_ = false, done_ = false, stop_ = false;
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
  const bool streamed = readSelected(c, record, [&](const Measurement& m) {
    zero.add(m);
    for (int ch : m.channels) last_read[ch] = count;
    check.add(m);
    ++count;
  });
  if (!streamed) return std::nullopt;
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
  r.samples = count - verdict.dropped;
  // runRoadFreeOneStep checks the samples kept once more, with their inputs.
  r.inputs = RoadFreeStream::inputsFor(c, readFrom(r.dropped));
  if (r.inputs != inputs) checkFrom(c, record, r.inputs, r.dropped);
  return r;
}

OfflineResult runRoadFreeOneStep(const EstimatorConfig& c, RecordStream& record,
                                 const CheckedRoadFreeStream& checked, SampleSink* samples) {
  return runRoadFreeOneStep(
      c,
      [&](const std::function<void(const Measurement&)>& take) {
        // Read on a thread of its own, a few blocks ahead of the filter: the
        // reading (a bag's decoding, alignment) costs no time of the run's.
        ReadAhead ahead(c, record);
        std::size_t k = 0;
        while (const std::vector<Measurement>* block = ahead.next()) {
          for (const Measurement& m : *block) {
            if (k++ >= checked.dropped) take(m);
          }
        }
      },
      checked.samples, checked.inputs, samples, RoadFreeStream::kObservedInterval);
}

}  // namespace pc_ekf
