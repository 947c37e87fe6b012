// Fuzz target: the measurement and road CSV readers (src/io/measurement_csv).
// Contract: the bytes either parse or throw pc_ekf::CsvError (file + line).
// What parses must satisfy the documented format: times finite, >= 0 and
// strictly increasing, values finite, channels ascending; and a measurement
// series written back by writeMeasurementCsv reads back identically.
// Anything else (other exceptions, crashes, sanitizer reports) is a bug.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>

#include "pc_ekf/io/measurement_csv.h"

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

void checkMeasurements(const pc_ekf::MeasurementSeries& series) {
  check(!series.empty());
  for (std::size_t i = 0; i < series.size(); ++i) {
    const pc_ekf::Measurement& m = series[i];
    check(std::isfinite(m.time) && m.time >= 0.0);
    if (i > 0) check(m.time > series[i - 1].time);
    check(static_cast<Eigen::Index>(m.channels.size()) == m.values.size());
    for (std::size_t k = 0; k < m.channels.size(); ++k) {
      check(m.channels[k] >= 0 && m.channels[k] < static_cast<int>(pc_ekf::rollPlaneChannels().size()));
      if (k > 0) check(m.channels[k] > m.channels[k - 1]);
    }
    check(m.values.allFinite());
  }
  // Round trip: 17 significant digits give back the same doubles.
  std::stringstream text;
  pc_ekf::writeMeasurementCsv(text, series);
  const pc_ekf::MeasurementSeries again = pc_ekf::readMeasurementCsv(text, "roundtrip.csv");
  check(again.size() == series.size());
  for (std::size_t i = 0; i < series.size(); ++i) {
    check(again[i].time == series[i].time && again[i].channels == series[i].channels &&
          again[i].values == series[i].values);
  }
}

void checkRoad(const pc_ekf::ContactSeries& road) {
  check(!road.t.empty() && road.heights.size() == 2 && road.heights[0].size() == road.t.size() &&
        road.heights[1].size() == road.t.size());
  for (std::size_t i = 0; i < road.t.size(); ++i) {
    check(std::isfinite(road.t[i]) && road.t[i] >= 0.0);
    check(std::isfinite(road.heights[0][i]) && std::isfinite(road.heights[1][i]));
    if (i > 0) check(road.t[i] > road.t[i - 1]);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  try {
    std::istringstream in(bytes);
    checkMeasurements(pc_ekf::readMeasurementCsv(in, "fuzz.csv"));
  } catch (const pc_ekf::CsvError&) {
  }
  try {
    std::istringstream in(bytes);
    checkRoad(pc_ekf::readContactRoadCsv(in, "fuzz_road.csv", {"y1", "y2"}));
  } catch (const pc_ekf::CsvError&) {
  }
  return 0;
}
