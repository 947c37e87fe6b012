// Aligning a body IMU with the suspension sensors (issue 29, docs/nodes.md
// "Clocks"). The two are separate streams with their own rates and stamps.
// The rule, shared by estimator_node and the bag reader (estimate_offline
// --bag, estimate_fleet), so that both give the same estimates:
//  - every suspension sample is a sample time; its stamp is kept;
//  - the IMU channels at that stamp are interpolated linearly between the
//    last IMU reading stamped at or before it and the first stamped at or
//    after it (a reading at the very stamp is taken as it is);
//  - the weights come from the integer nanosecond stamps, so both sides
//    compute the same doubles;
//  - no bracketing pair (before the first IMU reading, after the last, a
//    channel missing in one of the two) or a pair further apart than
//    max_gap (the IMU stopped): the sample keeps its suspension channels
//    only; nothing is dropped for being a few ms apart.
// Readings must come in stamp order: a reading stamped at or before the
// previous accepted one is refused (counted by the caller).
// ROS-free: stamps are int64 nanoseconds on any common clock.
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <deque>
#include <vector>

#include "pc_ekf/filter/measurement.h"

namespace pc_ekf {

// One IMU message as model channels.
struct ImuReading {
  std::int64_t stamp_ns = 0;
  std::vector<int> channels;  // model channel indices of the observed fields, ascending
  Eigen::VectorXd values;     // one per channel
  // One per channel: the message's variance, or NaN when the message gives
  // none ("unknown": the config's measurement noise applies).
  Eigen::VectorXd variances;
};

enum class ImuAlignment {
  kAligned,    // IMU channels added (at least one)
  kNoBracket,  // no reading at/after or at/before the stamp, or no channel in both
  kGap,        // the bracketing readings are more than max_gap apart
};

// The IMU channels at `stamp_ns` from the bracketing readings `before`
// (stamp <= stamp_ns) and `after` (stamp >= stamp_ns), merged into `m`
// (channels stay ascending; m.variances gets the interpolated message
// variances, NaN for the others). A channel is added when both readings have
// it, or when the reading at the very stamp has it. Variances: linear in the
// same weights when both are given, else NaN (the config's noise).
// Throws std::invalid_argument when the stamps do not bracket stamp_ns or a
// channel is already in `m`.
ImuAlignment addImuChannels(Measurement& m, std::int64_t stamp_ns, const ImuReading& before,
                            const ImuReading& after, std::int64_t max_gap_ns);

// The streaming form (estimator_node): IMU readings come in, suspension
// samples are aligned once a reading at or after their stamp is there.
class ImuAligner {
 public:
  explicit ImuAligner(double max_gap_seconds);
  // False (reading not kept) when stamped at or before the last accepted one.
  bool add(ImuReading reading);
  // A reading stamped at or after `stamp_ns` has arrived: align() can decide.
  bool ready(std::int64_t stamp_ns) const {
    return !readings_.empty() && readings_.back().stamp_ns >= stamp_ns;
  }
  // Aligns `m` stamped `stamp_ns` with what has arrived (kNoBracket when
  // nothing brackets it yet) and forgets readings no later sample needs
  // (samples come in stamp order).
  ImuAlignment align(Measurement& m, std::int64_t stamp_ns);
  // Stamps of the buffered readings around `stamp_ns` (-1: none).
  std::int64_t firstAtOrAfter(std::int64_t stamp_ns) const;
  std::int64_t lastAtOrBefore(std::int64_t stamp_ns) const;
  void reset() {
    readings_.clear();
    any_ = false;
  }
  std::size_t buffered() const { return readings_.size(); }
  std::int64_t maxGapNs() const { return max_gap_ns_; }
  // Stamp of the newest accepted reading (0 when none).
  std::int64_t lastStamp() const { return readings_.empty() ? last_stamp_ : readings_.back().stamp_ns; }

 private:
  std::int64_t max_gap_ns_;
  std::int64_t last_stamp_ = 0;
  bool any_ = false;
  std::deque<ImuReading> readings_;
};

struct ImuAlignmentCounts {
  int aligned = 0, no_bracket = 0, gap = 0;
  int readings_refused = 0;  // out of order or duplicate stamps
  void count(ImuAlignment a) {
    if (a == ImuAlignment::kAligned) ++aligned;
    if (a == ImuAlignment::kNoBracket) ++no_bracket;
    if (a == ImuAlignment::kGap) ++gap;
  }
};

// A whole record (the bag reader): `samples` in stamp order with their
// stamps `stamps_ns`; `readings` in arrival (bag) order, refused as the
// streaming form refuses them. Each sample is aligned with all readings.
MeasurementSeries alignImuRecord(const MeasurementSeries& samples,
                                 const std::vector<std::int64_t>& stamps_ns,
                                 const std::vector<ImuReading>& readings, double max_gap_seconds,
                                 ImuAlignmentCounts* counts = nullptr);

}  // namespace pc_ekf
