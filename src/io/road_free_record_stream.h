// A road-free one-step run (road.source none) on a record read as a stream
// (record_stream.h), with loadRecord's checks on a whole record: one pass
// for the checks, keeping nothing per sample in memory (the samples go to a
// temporary file), then the run on that file.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "pc_ekf/io/estimator_config.h"
#include "pc_ekf/io/offline_result.h"
#include "pc_ekf/io/record_stream.h"

namespace pc_ekf {

class RecordSpill;

struct CheckedRoadFreeStream {
  std::size_t samples = 0;  // after the dropped ones
  std::size_t dropped = 0;  // leading samples before every input had been read
  std::string warning;      // droppedWarning's ("" when none dropped)
  std::string unread;       // RoadFreeStream::unreadMotionWarning's ("" when none)
  std::vector<std::string> inputs;  // RoadFreeStream::inputsFor the samples kept
  // The samples as the checks read them, in a temporary file the run reads
  // back (null: the record is read again).
  std::shared_ptr<RecordSpill> spill;
};

// loadRecord's checks, in its order, on the record's channels that
// measurement.channels selects: `after_read` once the record has been read
// (its warnings printed), then ConfigError(name + ": " +
// zeroConventionProblem), then checkRoadFreeRecord's and
// runRoadFreeOneStep's. std::nullopt when the stream cannot be read as one.
std::optional<CheckedRoadFreeStream> checkRoadFreeStream(const EstimatorConfig& c,
                                                          RecordStream& record,
                                                          const std::string& name,
                                                          const std::function<void()>& after_read);

// runRoadFreeOneStep on the samples `checked` keeps, read once more: the
// numbers of the whole record's run.
OfflineResult runRoadFreeOneStep(const EstimatorConfig& c, RecordStream& record,
                                 const CheckedRoadFreeStream& checked, SampleSink* samples);

}  // namespace pc_ekf
