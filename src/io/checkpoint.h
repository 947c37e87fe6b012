// estimator_node's checkpoint: the filter state of the current run, its
// time origin and counters, and a hash of the configuration it was computed
// under (config_identity.h), as a small "key = value" text file. This file is
// the format; doubles are written in their shortest round-trip form
// (number_text.h) so that a resumed filter continues bit-exactly, the lines
// are read by key_value_text.h, and the file is replaced atomically
// (atomic_file.h): a reader sees the previous checkpoint or the new one, never half.
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>

#include "pc_ekf/filter/kept_samples.h"
#include "pc_ekf/filter/measurement.h"
#include "pc_ekf/io/config_identity.h"  // config_hash = fnv1a64(canonicalConfigText(config))
#include "pc_ekf/io/measurement_csv.h"

namespace pc_ekf {

// Unreadable, corrupt or foreign checkpoint: the message names the file and
// what is wrong.
class CheckpointError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A ROS stamp without ROS (seconds and nanoseconds since the epoch).
struct CheckpointStamp {
  std::uint32_t sec = 0, nsec = 0;
};

// One OneStepFilter: coefficient matrix, time since the origin, samples processed.
struct FilterCheckpoint {
  Eigen::MatrixXd x;  // (states + parameters) x S
  double time = 0.0;
  int samples = 0;
  // The working prior x was updated from (OneStepFilter::workingPrior,
  // parameters x S); empty: the prior. Written as `none` then; a checkpoint
  // without the key reads as empty.
  Eigen::MatrixXd working;
};

struct Checkpoint {
  std::uint64_t config_hash = 0;
  std::string road_mode;        // "analytic" or "topic" (EstimatorTimeline's RoadMode)
  CheckpointStamp origin;       // stamp of t = 0
  CheckpointStamp last_sample;  // stamp of the last processed sample
  FilterCheckpoint full;        // every sample
  FilterCheckpoint decimated;   // every k-th sample (coherence check)
  std::optional<Eigen::VectorXd> coherence_disagreement;  // last multi-rate comparison
  MeasurementSeries batch_samples;                        // kept for ~estimate_batch
  CheckpointStamp batch_last_stamp;
  // Road from road/profile (road_mode topic) that the filters still need: the
  // buffer from the sample at or before their oldest time (s since origin);
  // empty otherwise. road_last_stamp: the last road message accepted.
  ContactSeries road;  // one height column per contact of the model
  CheckpointStamp road_last_stamp;
  std::map<std::string, std::uint64_t> counters;  // node counters by name ([a-z0-9_.])
};

// Throws CheckpointError when the file cannot be written or renamed.
void writeCheckpoint(const Checkpoint& c, const std::string& path);

// A checkpoint taken in a sample callback and written later on another
// thread: everything but the batch samples, which stay in KeptSamples' shared
// blocks (a copy of 10^5 samples would cost the callback milliseconds) and
// are joined by writeCheckpoint on the writing thread.
struct CheckpointSnapshot {
  Checkpoint checkpoint;  // batch_samples empty
  KeptSamples batch;
};
void writeCheckpoint(const CheckpointSnapshot& s, const std::string& path);

// Strict: every key present once, matrices of the stated size, numbers
// finite. Throws CheckpointError naming the file and the key.
Checkpoint readCheckpoint(const std::string& path);

// Throws CheckpointError naming both hashes when `c` was written under
// another configuration.
void requireConfigHash(const Checkpoint& c, std::uint64_t current, const std::string& path);

}  // namespace pc_ekf
