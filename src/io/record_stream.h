// A record read sample by sample, from its start on every pass, instead of
// held whole: a road-free one-step run over an hour's bag or CSV then needs
// memory for neither (docs/method.md §4.10).
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "pc_ekf/filter/measurement.h"

namespace pc_ekf {

class RecordStream {
 public:
  virtual ~RecordStream() = default;
  // One pass: every sample in order to `take`. False (nothing taken) when
  // this record cannot be read as a stream and gives the same samples (a
  // bag whose joint_states stamps are out of bag order): read it whole.
  // Throws what reading the record whole throws.
  virtual bool read(const std::function<void(Measurement&)>& take) = 0;
  // The last pass's warnings about the record (a bag's, in readBag's order):
  // the first kKeptWarnings, and how many in all.
  static constexpr std::size_t kKeptWarnings = 5;
  const std::vector<std::string>& warnings() const { return warnings_; }
  std::size_t warningCount() const { return warning_count_; }

 protected:
  std::vector<std::string> warnings_;
  std::size_t warning_count_ = 0;
};

// A measurement CSV (measurement_csv.h), line by line.
std::unique_ptr<RecordStream> csvRecordStream(const std::string& path,
                                              const std::vector<std::string>& channels);

}  // namespace pc_ekf
