#include "pc_ekf/io/samples_csv.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "pc_ekf/io/number_text.h"

namespace pc_ekf {
namespace {

// An upper bound on one row's length: every cell a number of kG17Chars and
// its comma (the flags included), the index, the newline.
std::size_t rowBound(const SampleRecord& s, std::size_t loo_channels, int terms) {
  const std::size_t cells = 1 + static_cast<std::size_t>(s.mean.size()) *
                                    (2 + static_cast<std::size_t>(terms)) +
                            5 + loo_channels + 1;
  return 24 + cells * (kG17Chars + 1) + 1;
}

// One row at `o` (appendG17's %.17g digits); returns its end.
char* writeSampleRow(char* o, const SampleRecord& s, std::size_t loo_channels, int terms,
                     bool load_transfer_ratio) {
  const std::string index = std::to_string(s.index);
  o = std::copy(index.begin(), index.end(), o);
  *o++ = ',';
  o = writeG17(o, s.time);
  for (Eigen::Index i = 0; i < s.mean.size(); ++i) {
    *o++ = ',';
    o = writeG17(o, s.mean[i]);
    *o++ = ',';
    o = writeG17(o, s.stddev[i]);
    for (int j = 0; j < terms; ++j) {
      *o++ = ',';
      const double c = s.coefficients(i, j);
      if (c == 0.0 && !std::signbit(c)) {
        *o++ = '0';  // most coefficients of an affine expansion
      } else {
        o = writeG17(o, c);
      }
    }
  }
  *o++ = ',';
  o = writeG17(o, s.nis);
  for (bool flag : {s.nis_window_outside, s.band_nested, s.healthy}) {
    *o++ = ',';
    *o++ = flag ? '1' : '0';
  }
  // Empty cells: no leave-one-out error for this sample (a point left out).
  for (std::size_t i = 0; i < loo_channels; ++i) {
    *o++ = ',';
    if (static_cast<std::size_t>(s.loo_error.size()) == loo_channels) {
      o = writeG17(o, s.loo_error[i]);
    }
  }
  if (load_transfer_ratio) {
    *o++ = ',';
    o = writeG17(o, s.load_transfer_ratio);
  }
  *o++ = '\n';
  return o;
}

}  // namespace

SamplesCsv::SamplesCsv(const std::string& path) : path_(path), out_(path) {
  if (!out_) throw std::runtime_error(path + ": cannot write");
  thread_ = std::thread([this] { loop(); });
}

SamplesCsv::~SamplesCsv() {
  if (!open_.empty()) {
    std::lock_guard<std::mutex> lock(mutex_);
    waiting_.push_back(std::move(open_));
  }
  stop();
}

void SamplesCsv::begin(const SampleColumns& columns) {
  columns_ = columns;
  begun_ = true;
}

void SamplesCsv::add(SampleRecord record) {
  open_.push_back(std::move(record));
  if (open_.size() < kBlockRows) return;
  hand(std::move(open_));
  open_.clear();
  open_.reserve(kBlockRows);
}

void SamplesCsv::hand(Block block) {
  {
    std::unique_lock<std::mutex> lock(mutex_);
    room_.wait(lock, [this] { return waiting_.size() < kBlocksWaiting || !error_.empty(); });
    if (!error_.empty()) throw std::runtime_error(error_);
    waiting_.push_back(std::move(block));
  }
  wake_.notify_one();
}

void SamplesCsv::loop() {
  for (;;) {
    Block block;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [this] { return stopping_ || !waiting_.empty(); });
      if (waiting_.empty()) return;  // stopping, and every block written
      block = std::move(waiting_.front());
      waiting_.pop_front();
    }
    room_.notify_one();
    write(block);
  }
}

void SamplesCsv::write(const Block& block) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!error_.empty()) return;
  }
  // The first record's coefficient count names the columns of every row.
  if (!header_) writeHeader(static_cast<int>(block.front().coefficients.cols()));
  // Room for each row's bound before it is written (the rows' text is a
  // few times shorter: the buffer grows to about a block's text).
  std::size_t used = 0;
  for (const SampleRecord& r : block) {
    const std::size_t bound = rowBound(r, columns_.loo_channels.size(), terms_);
    if (buffer_.size() < used + bound) buffer_.resize(std::max(used + bound, 2 * buffer_.size()));
    char* const start = buffer_.data() + used;
    used += static_cast<std::size_t>(
        writeSampleRow(start, r, columns_.loo_channels.size(), terms_, columns_.load_transfer_ratio) -
        start);
  }
  out_.write(buffer_.data(), static_cast<std::streamsize>(used));
  if (!out_) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      error_ = path_ + ": writing failed";
    }
    room_.notify_one();  // a caller waiting for room throws
  }
}

void SamplesCsv::writeHeader(int terms) {
  std::string text = "index,t";
  for (const std::string& p : columns_.parameters) {
    text += ',' + p + "_mean," + p + "_stddev";
    for (int j = 0; j < terms; ++j) text += ',' + p + "_c" + std::to_string(j);
  }
  text += ",nis,nis_window_outside,band_nested,healthy";
  for (const std::string& channel : columns_.loo_channels) text += ",loo_" + channel;
  if (columns_.load_transfer_ratio) text += ",load_transfer_ratio";
  text += '\n';
  out_.write(text.data(), static_cast<std::streamsize>(text.size()));
  terms_ = terms;
  header_ = true;
}

void SamplesCsv::stop() {
  if (!thread_.joinable()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_one();
  thread_.join();
}

void SamplesCsv::close(const SampleColumns& columns) {
  if (!open_.empty()) hand(std::move(open_));
  open_.clear();
  if (!begun_) columns_ = columns;
  stop();
  if (!error_.empty()) throw std::runtime_error(error_);
  if (!header_) writeHeader(0);
  out_.close();
  if (!out_) throw std::runtime_error(path_ + ": writing failed");
}

}  // namespace pc_ekf
