// The record a tool estimates from: a bag (road and samples; the bag's road
// replaces the config's), a measurement CSV, or without either the synthetic
// data the config describes.
#pragma once

#include <algorithm>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/io/measurement_csv.h"
#include "pc_ekf/io/record_sensitivity.h"
#include "pc_ekf/io/record_stream.h"
#include "pc_ekf/io/road_free_record_stream.h"
#include "pc_ekf/io/road_free_stream.h"
#include "pc_ekf/tools/ros_on_demand.h"

namespace pc_ekf {

struct RecordInput {
  std::shared_ptr<const MechanicalModel> model;  // null: road-free readings not split
  MeasurementSeries series;
  // About the record as read (also on stderr): road-free samples dropped
  // before every input had been read.
  std::vector<std::string> warnings;
  // The sample interval a road-free stream reckons with: a synthetic drive's
  // is its sampling:'s, a record's comes from its stamps
  // (RoadFreeStream::kObservedInterval; sampling: is not read).
  double interval = RoadFreeStream::kObservedInterval;
};

// The seed of a run's random draws (the EnKF's, the synthetic data's):
// `--seed` when given, else truth.seed for a synthetic drive and 0 for a
// record (truth: describes synthetic drives only and is not read on one).
inline std::uint64_t runSeed(const EstimatorConfig& config, bool record,
                             const std::uint64_t* given) {
  if (given) return *given;
  return record ? 0 : config.truth.seed;
}

// A bag's warnings on stderr: the first five (of `first`) and how many more.
inline void printBagWarnings(const std::string& bag, const std::vector<std::string>& first,
                             std::size_t count) {
  for (std::size_t i = 0; i < first.size() && i < 5; ++i) {
    std::cerr << "[bag] " << bag << ": " << first[i] << "\n";
  }
  if (count > 5) std::cerr << "[bag] ... and " << count - 5 << " more warnings\n";
}

// `bag` and `csv` are paths ("" when not given; at most one of them).
// With road.source none the model is the road-free one built from the
// record (RoadFreeStream), the series its outputs; with `split_road_free`
// false the series stays the readings and the model null
// (runRoadFreeOneStep splits them as it goes).
inline RecordInput loadRecord(const EstimatorConfig& config, const std::string& bag,
                              const std::string& csv, std::uint64_t seed,
                              bool split_road_free = true) {
  RecordInput r;
  std::shared_ptr<const ContactRoad> bag_road;
  if (!bag.empty()) {
    BagRecord record = readBagOnDemand(bag, config);
    printBagWarnings(bag, record.warnings, record.warnings.size());
    if (config.road.source != RoadSource::kNone) {
      bag_road = std::make_shared<SampledRoad>(record.road_contacts.t, record.road_contacts.heights);
    }
    r.series = std::move(record.samples);
  }
  const bool road_free = config.road.source == RoadSource::kNone;
  if (!road_free) r.model = makeModel(config, makeRoad(config, bag_road));
  if (!csv.empty()) r.series = readMeasurementCsvFile(csv, config.model_type->channelNames());
  if (bag.empty() && csv.empty()) {
    // Road-free: the truth drives on truth.road (the estimator knows none).
    const auto truth = road_free ? truthOnItsRoad(config) : r.model;
    r.series = synthesizeFromConfig(config, *truth, seed);
    r.interval = config.sampling.interval();
  }
  // A recording may hold more channels than measurement.channels selects.
  const std::vector<int> selected = channelIndices(config);
  if (selected.size() < config.model_type->channelNames().size()) {
    r.series = onlyChannels(r.series, selected);
  }
  const std::string zero = zeroConventionProblem(config, r.series);
  if (!zero.empty()) {
    throw ConfigError((bag.empty() ? csv : bag) + ": " + zero);
  }
  if (road_free) {
    const std::string unread = RoadFreeStream::unreadMotionWarning(config, [&](int ch) {
      return std::any_of(r.series.begin(), r.series.end(), [ch](const Measurement& m) {
        return std::find(m.channels.begin(), m.channels.end(), ch) != m.channels.end();
      });
    });
    if (!unread.empty()) {
      const std::string& name = !bag.empty() ? bag : !csv.empty() ? csv : config.source;
      std::cerr << "[road-free] " << name << ": " << unread << "\n";
      r.warnings.push_back(unread);
    }
  }
  if (road_free && split_road_free) {
    RoadFreeRecord split = roadFreeRecord(config, r.series, r.interval);
    r.model = split.model;
    r.series = std::move(split.outputs);
    if (!split.warning.empty()) {
      const std::string& name = !bag.empty() ? bag : !csv.empty() ? csv : config.source;
      std::cerr << "[road-free] " << name << ": " << split.warning << "\n";
      r.warnings.push_back(split.warning);
    }
  } else if (road_free) {
    // A sample the stream refuses: refused now; the leading samples before
    // every input has been read dropped as roadFreeRecord drops them.
    const RoadFreeCheck check = checkRoadFreeRecord(config, r.series);
    if (check.dropped > 0) {
      r.series.erase(r.series.begin(), r.series.begin() + static_cast<std::ptrdiff_t>(check.dropped));
      const std::string& name = !bag.empty() ? bag : !csv.empty() ? csv : config.source;
      std::cerr << "[road-free] " << name << ": " << check.warning << "\n";
      r.warnings.push_back(check.warning);
    }
  }
  return r;
}

// The record's sensitivity (printed as a table when `print`) and the config
// with tolerances_prune applied; what was fixed is printed and kept in `pruned`.
inline EstimatorConfig sensitivityAndPrune(const EstimatorConfig& config, const RecordInput& record,
                                           bool print, PriorSensitivity* sensitivity,
                                           std::vector<std::string>* pruned) {
  if (!print && !(config.tolerances_prune > 0.0)) return config;
  *sensitivity = recordSensitivity(config, record.model, sampleTimes(record.series));
  if (print) std::cerr << sensitivityTable(*sensitivity);
  const EstimatorConfig out = pruneTolerances(config, *sensitivity, pruned);
  for (const auto& line : *pruned) std::cerr << "[tolerances_prune] " << line << "\n";
  return out;
}

// A bag or CSV for road-free one-step (loadRecord with split_road_free
// false) read as a stream instead of whole: checked now with loadRecord's
// messages, estimated by runRoadFreeOneStep(config, *stream, checked, ...).
struct StreamedRecord {
  std::unique_ptr<RecordStream> stream;
  CheckedRoadFreeStream checked;
  std::vector<std::string> warnings;  // as RecordInput's
};
// std::nullopt when there is no such record or it is to be read whole.
inline std::optional<StreamedRecord> streamRoadFreeRecord(const EstimatorConfig& config,
                                                          const std::string& bag,
                                                          const std::string& csv) {
  if (bag.empty() == csv.empty() || config.road.source != RoadSource::kNone) return std::nullopt;
  StreamedRecord r;
  r.stream = !bag.empty() ? bagRecordStreamOnDemand(bag, config)
                          : csvRecordStream(csv, config.model_type->channelNames());
  const std::string& name = !bag.empty() ? bag : csv;
  const auto checked = checkRoadFreeStream(config, *r.stream, name, [&] {
    if (!bag.empty()) printBagWarnings(bag, r.stream->warnings(), r.stream->warningCount());
  });
  if (!checked) return std::nullopt;
  r.checked = *checked;
  for (const std::string* w : {&checked->warning, &checked->unread}) {
    if (w->empty()) continue;
    std::cerr << "[road-free] " << name << ": " << *w << "\n";
    r.warnings.push_back(*w);
  }
  return r;
}

}  // namespace pc_ekf
