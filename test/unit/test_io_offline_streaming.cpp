// estimate_offline keeps nothing per sample: the records go to a sink as the
// run makes them, once per sample and in order, with the numbers the run
// reports; samples.csv is written from them row by row and reads back as
// the same doubles; road-free one-step splits the readings as the filter
// goes (forgetting the inputs no filter reads again) and gives the numbers
// of the whole record's split.
#include <gtest/gtest.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/io/offline_estimation.h"
#include "pc_ekf/io/road_free_stream.h"
#include "pc_ekf/io/samples_csv.h"

namespace pc_ekf {
namespace {

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

bool sameBits(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  if (a.rows() != b.rows() || a.cols() != b.cols()) return false;
  for (Eigen::Index i = 0; i < a.size(); ++i) {
    if (!sameBits(a.data()[i], b.data()[i])) return false;
  }
  return true;
}

bool sameRecord(const SampleRecord& a, const SampleRecord& b) {
  return a.index == b.index && sameBits(a.time, b.time) && sameBits(a.mean, b.mean) &&
         sameBits(a.stddev, b.stddev) && sameBits(a.coefficients, b.coefficients) &&
         sameBits(a.nis, b.nis) && a.nis_window_outside == b.nis_window_outside &&
         a.band_nested == b.band_nested && a.healthy == b.healthy &&
         sameBits(a.loo_error, b.loo_error);
}

// What a sink was given; `also` (optional) gets it too.
struct Collected : SampleSink {
  SampleSink* also = nullptr;
  int begun = 0;
  bool added_before_begin = false;
  SampleColumns columns;
  std::vector<SampleRecord> records;
  void begin(const SampleColumns& c) override {
    ++begun;
    columns = c;
    if (also) also->begin(c);
  }
  void add(SampleRecord r) override {
    added_before_begin = added_before_begin || begun == 0;
    records.push_back(r);
    if (also) also->add(r);
  }
};

std::string withoutWallTime(std::string json) {
  const std::size_t at = json.find("\"wall_time_s\"");
  return json.erase(at, json.find('\n', at) - at);
}

std::string scratchDir(const std::string& name) {
  return (std::filesystem::temp_directory_path() /
          ("pc_ekf_streaming_" + std::to_string(::getpid())) / name)
      .string();
}

struct Bump {
  EstimatorConfig c;
  std::shared_ptr<const MechanicalModel> model;
  MeasurementSeries data;
  explicit Bump(int samples) {
    c = loadConfigFile(std::string(PC_EKF_SOURCE_DIR) + "/config/speed_bump.yaml");
    c.sampling.samples = samples;
    model = makeModel(c, makeRoad(c));
    data = synthesizeFromConfig(c, *model, c.truth.seed);
  }
};

TEST(OfflineStreaming, SinkGetsEveryRecordOnceInOrder) {
  const Bump many(300), few(10);
  struct Case {
    EstimationMethod method;
    const Bump* run;
    std::size_t records;
  };
  for (const Case& k : {Case{EstimationMethod::kOneStep, &many, 300},
                        Case{EstimationMethod::kEnkf, &many, 300},
                        Case{EstimationMethod::kEsMda, &many, 1},
                        Case{EstimationMethod::kGrid, &few, 1}}) {
    SCOPED_TRACE(toString(k.method));
    const Bump& b = *k.run;
    Collected sink;
    const OfflineResult r =
        runOfflineEstimation(b.c, b.data, b.model, k.method, 1, {}, nullptr, &sink);
    EXPECT_EQ(sink.begun, 1);
    EXPECT_FALSE(sink.added_before_begin);
    ASSERT_EQ(sink.records.size(), k.records);
    ASSERT_EQ(sink.columns.parameters.size(), r.parameters.size());
    for (std::size_t i = 0; i < r.parameters.size(); ++i) {
      EXPECT_EQ(sink.columns.parameters[i], r.parameters[i].name);
      // The reported estimate is the last record's.
      const auto e = static_cast<Eigen::Index>(i);
      EXPECT_TRUE(sameBits(r.parameters[i].mean, sink.records.back().mean[e]));
      EXPECT_TRUE(sameBits(r.parameters[i].stddev, sink.records.back().stddev[e]));
    }
    EXPECT_EQ(sink.columns.loo_channels, r.loo_channels);
    EXPECT_TRUE(sameRecord(sink.records.back(), r.last_record));
    if (k.records > 1) {
      for (std::size_t i = 0; i < sink.records.size(); ++i) {
        ASSERT_EQ(sink.records[i].index, static_cast<int>(i + 1));
        ASSERT_TRUE(sameBits(sink.records[i].time, b.data[i].time));
      }
    }
    // A sink changes nothing the run reports.
    const OfflineResult alone = runOfflineEstimation(b.c, b.data, b.model, k.method, 1);
    EXPECT_EQ(withoutWallTime(toJson(alone)), withoutWallTime(toJson(r)));
  }
}

// Splits a CSV line at commas (empty cells kept).
std::vector<std::string> cells(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream in(line);
  for (std::string cell; std::getline(in, cell, ',');) out.push_back(cell);
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

TEST(OfflineStreaming, SamplesCsvHoldsEveryRecordBitForBit) {
  // 300 rows: several blocks of the writer's thread, and its queue full.
  const Bump b(300);
  const std::string dir = scratchDir("rows");
  Collected sink;
  OfflineOutputs out(dir);
  sink.also = &out;
  const OfflineResult r =
      runOfflineEstimation(b.c, b.data, b.model, EstimationMethod::kOneStep, 1, {}, nullptr, &sink);
  out.finish(r);
  ASSERT_EQ(sink.records.size(), 300u);

  std::ifstream in(dir + "/samples.csv");
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  const int terms = static_cast<int>(sink.records[0].coefficients.cols());
  std::string header = "index,t";
  for (const std::string& p : sink.columns.parameters) {
    header += "," + p + "_mean," + p + "_stddev";
    for (int j = 0; j < terms; ++j) header += "," + p + "_c" + std::to_string(j);
  }
  header += ",nis,nis_window_outside,band_nested,healthy";
  for (const std::string& ch : sink.columns.loo_channels) header += ",loo_" + ch;
  EXPECT_EQ(line, header);
  const auto number = [](const std::string& cell) { return std::strtod(cell.c_str(), nullptr); };
  std::size_t row = 0;
  for (; std::getline(in, line); ++row) {
    ASSERT_LT(row, sink.records.size());
    const SampleRecord& s = sink.records[row];
    const std::vector<std::string> c = cells(line);
    const std::size_t n = static_cast<std::size_t>(s.mean.size());
    ASSERT_EQ(c.size(), 2 + n * (2 + terms) + 4 + sink.columns.loo_channels.size()) << line;
    EXPECT_EQ(c[0], std::to_string(s.index));
    EXPECT_TRUE(sameBits(number(c[1]), s.time));
    std::size_t at = 2;
    for (std::size_t i = 0; i < n; ++i) {
      const auto e = static_cast<Eigen::Index>(i);
      EXPECT_TRUE(sameBits(number(c[at++]), s.mean[e])) << "row " << row;
      EXPECT_TRUE(sameBits(number(c[at++]), s.stddev[e])) << "row " << row;
      for (int j = 0; j < terms; ++j) {
        EXPECT_TRUE(sameBits(number(c[at++]), s.coefficients(e, j))) << "row " << row;
      }
    }
    EXPECT_TRUE(sameBits(number(c[at++]), s.nis));
    EXPECT_EQ(c[at++], s.nis_window_outside ? "1" : "0");
    EXPECT_EQ(c[at++], s.band_nested ? "1" : "0");
    EXPECT_EQ(c[at++], s.healthy ? "1" : "0");
    for (std::size_t i = 0; i < sink.columns.loo_channels.size(); ++i, ++at) {
      if (s.loo_error.size() == 0) {
        EXPECT_EQ(c[at], "");
      } else {
        EXPECT_TRUE(sameBits(number(c[at]), s.loo_error[static_cast<Eigen::Index>(i)]));
      }
    }
  }
  EXPECT_EQ(row, sink.records.size());
  std::filesystem::remove_all(std::filesystem::path(dir).parent_path());
}

TEST(OfflineStreaming, WithoutRecordsTheHeaderAloneAndNoStaleResult) {
  const std::string dir = scratchDir("empty");
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/result.json") << "{\"from\": \"an earlier run\"}\n";
  OfflineResult r;
  r.parameters = {{"a", 1.0, 0.1, 0.0, 0.1}, {"b", 2.0, 0.2, 0.0, 0.2}};
  r.loo_channels = {"u1"};
  {
    OfflineOutputs out(dir);
    // Until the run finishes there is no result.json (none of an earlier run).
    EXPECT_FALSE(std::filesystem::exists(dir + "/result.json"));
    out.finish(r);
  }
  std::ifstream in(dir + "/samples.csv");
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(),
            "index,t,a_mean,a_stddev,b_mean,b_stddev,nis,nis_window_outside,band_nested,healthy,"
            "loo_u1\n");
  EXPECT_TRUE(std::filesystem::exists(dir + "/result.json"));
  std::filesystem::remove_all(std::filesystem::path(dir).parent_path());
}

TEST(OfflineStreaming, AFailedWriteIsAnError) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  const Bump b(300);
  Collected collected;
  runOfflineEstimation(b.c, b.data, b.model, EstimationMethod::kOneStep, 1, {}, nullptr,
                       &collected);
  SamplesCsv csv("/dev/full");
  const auto write = [&] {
    csv.begin(collected.columns);
    for (const SampleRecord& s : collected.records) csv.add(s);
    csv.close(collected.columns);
  };
  EXPECT_THROW(write(), std::runtime_error);
}

// Road-free one-step on the raw readings, split as the filter goes and the
// inputs forgotten behind it, against the whole record split first: the
// same records and JSON, linearised at the mean (its horizon's windows
// re-read the inputs) and by collocation with re-linearisation (re-runs
// from the start while it lasts).
TEST(OfflineStreaming, RoadFreeStreamGivesTheWholeSplitsNumbers) {
  struct Case {
    const char* linearization;
    double duration;
  };
  for (const Case& k : {Case{"mean", 60.0}, Case{"collocation", 25.0}}) {
    SCOPED_TRACE(k.linearization);
    YAML::Node root = YAML::LoadFile(std::string(PC_EKF_SOURCE_DIR) + "/config/vehicle_imu.yaml");
    root["sampling"]["samples"] = static_cast<int>(200 * k.duration);
    root["sampling"]["duration"] = k.duration;
    root["filter"]["linearization"] = k.linearization;
    // The load's re-open (as shipped) goes with the mean's linearisation only.
    if (std::string(k.linearization) == "collocation") root["filter"]["reopen"]["mode"] = "off";
    const EstimatorConfig c = parseConfig(root, "vehicle_imu.yaml");
    const MeasurementSeries readings = synthesizeFromConfig(c, *truthOnItsRoad(c), c.truth.seed);
    Collected streamed, whole;
    const OfflineResult a = runRoadFreeOneStep(c, readings, &streamed);
    const RoadFreeRecord split = roadFreeRecord(c, readings);
    const OfflineResult b = runOfflineEstimation(c, split.outputs, split.model,
                                                 EstimationMethod::kOneStep, c.truth.seed, {},
                                                 nullptr, &whole);
    EXPECT_EQ(withoutWallTime(toJson(a)), withoutWallTime(toJson(b)));
    ASSERT_EQ(streamed.records.size(), readings.size());
    ASSERT_EQ(whole.records.size(), readings.size());
    EXPECT_EQ(streamed.columns.loo_channels, whole.columns.loo_channels);
    for (std::size_t i = 0; i < readings.size(); ++i) {
      ASSERT_TRUE(sameRecord(streamed.records[i], whole.records[i])) << "sample " << i + 1;
    }
  }
}

TEST(OfflineStreaming, ARefusedReadingFailsBeforeTheRun) {
  EstimatorConfig c = loadConfigFile(std::string(PC_EKF_SOURCE_DIR) + "/config/vehicle_imu.yaml");
  c.sampling.samples = 200;
  c.sampling.duration = 1.0;
  MeasurementSeries readings = synthesizeFromConfig(c, *truthOnItsRoad(c), 1);
  readings[150].time = readings[149].time;  // not after the sample before
  Collected sink;
  try {
    runRoadFreeOneStep(c, readings, &sink);
    ADD_FAILURE() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("sample 151"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(sink.records.empty());
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
