// estimate_offline's road-free one-step on a bag or CSV read as a stream
// (bagRecordStream, csvRecordStream, checkRoadFreeStream) gives exactly the
// numbers, rows and warnings of the whole record read first (readBag or
// readMeasurementCsvFile, then loadRecord's checks and runRoadFreeOneStep).
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "bag_test_support.h"
#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/io/measurement_csv.h"
#include "pc_ekf/io/offline_estimation.h"
#include "pc_ekf/io/road_free_record_stream.h"
#include "pc_ekf/io/road_free_stream.h"
#include "pc_ekf/ros/bag_io.h"
#include "pc_ekf/ros/bag_stream.h"

namespace pc_ekf {
namespace {

using test::quote;
using test::ScratchDir;

// test_bag_estimate_offline's late-IMU bag: samples every 5 ms from 5 ms,
// the IMU at 400 Hz from 11.2 ms, so the first two samples have no gyro_x.
std::string lateImuConfig(const ScratchDir& dir) {
  std::string yaml =
      test::readText(std::string(PC_EKF_SOURCE_DIR) + "/test/ros/estimator_road_free.yaml");
  const std::string road =
      "    source: iso8608\n    speed_kmh: 36.0\n    iso8608: {class: B, seed: 3, correlation: 0.0}\n";
  const auto at = yaml.find(road);
  EXPECT_NE(at, std::string::npos);
  if (at != std::string::npos) {
    yaml.replace(at, road.size(),
                 "    source: course\n"
                 "    course:\n"
                 "      - {type: iso8608, class: B, speed_kmh: 36.0, duration: 0.8}\n"
                 "      - {type: rest, duration: 0.4}\n"
                 "      - {type: iso8608, class: C, speed_kmh: 54.0, duration: 0.8}\n");
  }
  const std::string path = dir.file("late_imu.yaml");
  std::ofstream(path) << yaml;
  return path;
}

// The run's result.json, pdfs.csv and samples.csv (wall time left out).
std::string outputs(const std::string& dir, OfflineResult r) {
  r.wall_seconds = 0.0;
  return test::readText(dir + "/samples.csv") + "\n--\n" + toJson(r);
}

// loadRecord's whole-record path: channels selected, zero convention,
// leading samples dropped, then runRoadFreeOneStep.
std::string wholeRecordRun(const EstimatorConfig& c, MeasurementSeries series,
                           const std::string& out, RoadFreeCheck* check) {
  const std::vector<int> selected = channelIndices(c);
  if (selected.size() < c.model_type->channelNames().size()) series = onlyChannels(series, selected);
  EXPECT_EQ(zeroConventionProblem(c, series), "");
  *check = checkRoadFreeRecord(c, series);
  series.erase(series.begin(), series.begin() + static_cast<std::ptrdiff_t>(check->dropped));
  OfflineOutputs sink(out);
  const OfflineResult r = runRoadFreeOneStep(c, series, &sink);
  sink.finish(r);
  return outputs(out, r);
}

std::string streamedRun(const EstimatorConfig& c, RecordStream& stream, const std::string& out,
                        const RoadFreeCheck& whole) {
  bool read = false;
  const auto checked = checkRoadFreeStream(c, stream, "record", [&] { read = true; });
  EXPECT_TRUE(read);
  if (!checked) {
    ADD_FAILURE() << "not streamed";
    return "";
  }
  EXPECT_EQ(checked->dropped, whole.dropped);
  EXPECT_EQ(checked->warning, whole.warning);
  OfflineOutputs sink(out);
  const OfflineResult r = runRoadFreeOneStep(c, stream, *checked, &sink);
  sink.finish(r);
  return outputs(out, r);
}

TEST(RoadFreeStreamed, BagAndCsvGiveTheWholeRecordsNumbers) {
  ScratchDir dir;
  const std::string config_path = lateImuConfig(dir);
  const std::string bag = dir.file("late_imu.bag"), csv = dir.file("late_imu.csv");
  const auto made = test::run(dir, PC_EKF_EXE_SYNTHESIZE_BAG,
                              "--config " + quote(config_path) + " --output " + quote(bag) +
                                  " --csv " + quote(csv) + " --imu-rate 400 --imu-offset 0.0112");
  ASSERT_EQ(made.status, 0) << made.err;
  const EstimatorConfig c = loadConfigFile(config_path);
  ASSERT_EQ(c.road.source, RoadSource::kNone);

  // The bag: its first two samples (no IMU reading before them) dropped.
  const BagReadOptions options = bagReadOptions(c);
  const BagRecord record = readBag(bag, options);
  RoadFreeCheck whole_check;
  const std::string whole = wholeRecordRun(c, record.samples, dir.file("whole"), &whole_check);
  EXPECT_EQ(whole_check.dropped, 2u);
  auto stream = bagRecordStream(bag, options);
  const std::string streamed = streamedRun(c, *stream, dir.file("streamed"), whole_check);
  EXPECT_NE(whole.find("\"samples\": 398,"), std::string::npos) << whole.substr(whole.find("--"));
  EXPECT_TRUE(whole == streamed) << "whole:\n" << whole.substr(whole.size() - 2000)
                                 << "\nstreamed:\n" << streamed.substr(streamed.size() - 2000);
  // readBag's warnings: the first kept, all counted.
  EXPECT_EQ(stream->warningCount(), record.warnings.size());
  for (std::size_t i = 0; i < stream->warnings().size(); ++i) {
    EXPECT_EQ(stream->warnings()[i], record.warnings[i]);
  }

  // The CSV (every channel of every sample as written).
  RoadFreeCheck csv_check;
  const std::string whole_csv = wholeRecordRun(
      c, readMeasurementCsvFile(csv, c.model_type->channelNames()), dir.file("whole_csv"), &csv_check);
  auto csv_stream = csvRecordStream(csv, c.model_type->channelNames());
  EXPECT_TRUE(whole_csv == streamedRun(c, *csv_stream, dir.file("streamed_csv"), csv_check));
}

// A record the checks refuse is refused before the run, with the whole
// record's message.
TEST(RoadFreeStreamed, ARefusedRecordFailsTheChecksAsTheWholeRecordDoes) {
  ScratchDir dir;
  const std::string config_path = lateImuConfig(dir);
  const EstimatorConfig c = loadConfigFile(config_path);
  const std::vector<std::string> names = c.model_type->channelNames();
  MeasurementSeries series;
  const std::string csv = dir.file("record.csv");
  {
    const std::string bag = dir.file("r.bag");
    const auto made = test::run(dir, PC_EKF_EXE_SYNTHESIZE_BAG,
                                "--config " + quote(config_path) + " --output " + quote(bag) +
                                    " --csv " + quote(csv));
    ASSERT_EQ(made.status, 0) << made.err;
    series = readMeasurementCsvFile(csv, names);
  }
  // No sample reads the travel u1: every sample waits for it, none is left.
  ASSERT_GT(series.size(), 60u);
  for (Measurement& m : series) m = onlyChannels(m, {1, 2, 3, 4, 5, 6});
  {
    std::ofstream out(csv);
    writeMeasurementCsv(out, series, names);
  }
  std::string whole_error, streamed_error;
  try {
    checkRoadFreeRecord(c, readMeasurementCsvFile(csv, names));
  } catch (const ConfigError& e) {
    whole_error = e.what();
  }
  auto stream = csvRecordStream(csv, names);
  try {
    checkRoadFreeStream(c, *stream, csv, [] {});
  } catch (const ConfigError& e) {
    streamed_error = e.what();
  }
  EXPECT_NE(whole_error.find("no sample has every road-free input"), std::string::npos)
      << whole_error;
  EXPECT_EQ(streamed_error, whole_error);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
