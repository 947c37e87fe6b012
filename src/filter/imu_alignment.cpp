#include "pc_ekf/filter/imu_alignment.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace pc_ekf {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Index of channel c in r, or -1.
int find(const ImuReading& r, int c) {
  for (std::size_t i = 0; i < r.channels.size(); ++i) {
    if (r.channels[i] == c) return static_cast<int>(i);
  }
  return -1;
}

}  // namespace

ImuAlignment addImuChannels(Measurement& m, std::int64_t stamp_ns, const ImuReading& before,
                            const ImuReading& after, std::int64_t max_gap_ns) {
  if (before.stamp_ns > stamp_ns || after.stamp_ns < stamp_ns) {
    throw std::invalid_argument("addImuChannels: IMU stamps " + std::to_string(before.stamp_ns) +
                                " and " + std::to_string(after.stamp_ns) +
                                " ns do not bracket the sample at " + std::to_string(stamp_ns));
  }
  if (after.stamp_ns - before.stamp_ns > max_gap_ns) return ImuAlignment::kGap;
  const std::int64_t span = after.stamp_ns - before.stamp_ns;
  // Weight of `after`; exact 0 or 1 at either end.
  const double w = span == 0 ? 0.0
                             : static_cast<double>(stamp_ns - before.stamp_ns) /
                                   static_cast<double>(span);
  std::vector<int> channels;
  std::vector<double> values, variances;
  const auto addFrom = [&](const ImuReading& r, int i) {
    channels.push_back(r.channels[static_cast<std::size_t>(i)]);
    values.push_back(r.values[i]);
    variances.push_back(r.variances.size() == r.values.size() ? r.variances[i] : kNaN);
  };
  if (w == 0.0 || w == 1.0) {
    const ImuReading& at = w == 0.0 ? before : after;
    for (std::size_t i = 0; i < at.channels.size(); ++i) addFrom(at, static_cast<int>(i));
  } else {
    for (std::size_t i = 0; i < before.channels.size(); ++i) {
      const int c = before.channels[i];
      const int j = find(after, c);
      if (j < 0) continue;
      const int k = static_cast<int>(i);
      channels.push_back(c);
      values.push_back((1.0 - w) * before.values[k] + w * after.values[j]);
      const bool given = before.variances.size() == before.values.size() &&
                         after.variances.size() == after.values.size() &&
                         std::isfinite(before.variances[k]) && std::isfinite(after.variances[j]);
      variances.push_back(given ? (1.0 - w) * before.variances[k] + w * after.variances[j] : kNaN);
    }
  }
  if (channels.empty()) return ImuAlignment::kNoBracket;

  // Merge, channels ascending; existing entries keep their variance (or NaN).
  const std::size_t n = m.channels.size();
  const bool had_variances = m.variances.size() == m.values.size() && n > 0;
  std::vector<int> out_channels;
  std::vector<double> out_values, out_variances;
  std::size_t a = 0, b = 0;
  while (a < n || b < channels.size()) {
    if (a < n && b < channels.size() && m.channels[a] == channels[b]) {
      throw std::invalid_argument("addImuChannels: channel " + std::to_string(channels[b]) +
                                  " is already in the sample");
    }
    if (b >= channels.size() || (a < n && m.channels[a] < channels[b])) {
      out_channels.push_back(m.channels[a]);
      out_values.push_back(m.values[static_cast<Eigen::Index>(a)]);
      out_variances.push_back(had_variances ? m.variances[static_cast<Eigen::Index>(a)] : kNaN);
      ++a;
    } else {
      out_channels.push_back(channels[b]);
      out_values.push_back(values[b]);
      out_variances.push_back(variances[b]);
      ++b;
    }
  }
  m.channels = std::move(out_channels);
  const auto size = static_cast<Eigen::Index>(out_values.size());
  m.values = Eigen::Map<const Eigen::VectorXd>(out_values.data(), size);
  bool any_variance = false;
  for (double v : out_variances) any_variance = any_variance || std::isfinite(v);
  if (any_variance) {
    m.variances = Eigen::Map<const Eigen::VectorXd>(out_variances.data(), size);
  } else {
    m.variances.resize(0);
  }
  return ImuAlignment::kAligned;
}

ImuAligner::ImuAligner(double max_gap_seconds)
    : max_gap_ns_(static_cast<std::int64_t>(std::llround(max_gap_seconds * 1e9))) {
  if (!(max_gap_seconds > 0.0)) throw std::invalid_argument("ImuAligner: max_gap must be > 0");
}

bool ImuAligner::add(ImuReading reading) {
  if (any_ && reading.stamp_ns <= lastStamp()) return false;
  any_ = true;
  last_stamp_ = reading.stamp_ns;
  readings_.push_back(std::move(reading));
  return true;
}

std::int64_t ImuAligner::firstAtOrAfter(std::int64_t stamp_ns) const {
  for (const ImuReading& r : readings_) {
    if (r.stamp_ns >= stamp_ns) return r.stamp_ns;
  }
  return -1;
}

std::int64_t ImuAligner::lastAtOrBefore(std::int64_t stamp_ns) const {
  std::int64_t out = -1;
  for (const ImuReading& r : readings_) {
    if (r.stamp_ns > stamp_ns) break;
    out = r.stamp_ns;
  }
  return out;
}

ImuAlignment ImuAligner::align(Measurement& m, std::int64_t stamp_ns) {
  // The last reading at or before the stamp, and the first at or after it.
  std::size_t first_after = readings_.size();
  for (std::size_t i = 0; i < readings_.size(); ++i) {
    if (readings_[i].stamp_ns >= stamp_ns) {
      first_after = i;
      break;
    }
  }
  const bool has_after = first_after < readings_.size();
  const bool exact = has_after && readings_[first_after].stamp_ns == stamp_ns;
  const bool has_before = exact || first_after > 0;
  const std::size_t before = exact ? first_after : first_after - 1;
  ImuAlignment result = ImuAlignment::kNoBracket;
  if (has_after && has_before) {
    result = addImuChannels(m, stamp_ns, readings_[before], readings_[first_after], max_gap_ns_);
  }
  // Later samples are stamped at or after this one: they need nothing older
  // than the last reading at or before it.
  if (has_before) {
    readings_.erase(readings_.begin(), readings_.begin() + static_cast<std::ptrdiff_t>(before));
  }
  return result;
}

MeasurementSeries alignImuRecord(const MeasurementSeries& samples,
                                 const std::vector<std::int64_t>& stamps_ns,
                                 const std::vector<ImuReading>& readings, double max_gap_seconds,
                                 ImuAlignmentCounts* counts) {
  if (stamps_ns.size() != samples.size()) {
    throw std::invalid_argument("alignImuRecord: " + std::to_string(stamps_ns.size()) +
                                " stamps for " + std::to_string(samples.size()) + " samples");
  }
  ImuAlignmentCounts local;
  ImuAlignmentCounts& n = counts ? *counts : local;
  ImuAligner aligner(max_gap_seconds);
  for (const ImuReading& r : readings) {
    if (!aligner.add(r)) ++n.readings_refused;
  }
  MeasurementSeries out = samples;
  for (std::size_t k = 0; k < out.size(); ++k) {
    if (k > 0 && stamps_ns[k] < stamps_ns[k - 1]) {
      throw std::invalid_argument("alignImuRecord: samples not in stamp order");
    }
    n.count(aligner.align(out[k], stamps_ns[k]));
  }
  return out;
}

}  // namespace pc_ekf
