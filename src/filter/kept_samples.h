// The samples a run keeps for the batch update. Appended one at a time and
// copied for every checkpoint while the run goes on: stored in blocks that
// are immutable once full and shared between copies, so a copy costs one
// pointer per full block plus the open block, not the whole record.
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include "pc_ekf/filter/measurement.h"

namespace pc_ekf {

class KeptSamples {
 public:
  static constexpr std::size_t kBlockSize = 1024;

  KeptSamples() = default;
  explicit KeptSamples(const MeasurementSeries& series);

  void push_back(const Measurement& m);
  void clear();
  std::size_t size() const { return full_.size() * kBlockSize + open_.size(); }
  bool empty() const { return size() == 0; }
  const Measurement& back() const;
  // Every sample in order (a full copy: for the batch update and the file).
  MeasurementSeries series() const;

 private:
  std::vector<std::shared_ptr<const MeasurementSeries>> full_;  // kBlockSize each
  MeasurementSeries open_;                                       // fewer than kBlockSize
};

}  // namespace pc_ekf
