#include "pc_ekf/filter/kept_samples.h"

#include <stdexcept>

namespace pc_ekf {

KeptSamples::KeptSamples(const MeasurementSeries& series) {
  for (const Measurement& m : series) push_back(m);
}

void KeptSamples::push_back(const Measurement& m) {
  if (open_.empty()) open_.reserve(kBlockSize);
  open_.push_back(m);
  if (open_.size() == kBlockSize) {
    full_.push_back(std::make_shared<const MeasurementSeries>(std::move(open_)));
    open_ = MeasurementSeries();
  }
}

void KeptSamples::clear() {
  full_.clear();
  open_.clear();
}

const Measurement& KeptSamples::back() const {
  if (!open_.empty()) return open_.back();
  if (full_.empty()) throw std::out_of_range("KeptSamples::back: no samples");
  return full_.back()->back();
}

MeasurementSeries KeptSamples::series() const {
  MeasurementSeries out;
  out.reserve(size());
  for (const auto& block : full_) out.insert(out.end(), block->begin(), block->end());
  out.insert(out.end(), open_.begin(), open_.end());
  return out;
}

}  // namespace pc_ekf
