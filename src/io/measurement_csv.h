// The measurement and road CSV formats of INTERFACE.md:
//   measurements: header t,u1,u2,v1,v2; empty cell or nan = not observed
//   road:         header t,y1,y2
// SI units, one sample a row, time strictly increasing.
#pragma once

#include <istream>
#include <stdexcept>
#include <string>
#include <vector>

#include "filter/measurement.h"

namespace pc_ekf {

// Names the file, the line and what was expected.
class CsvError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

MeasurementSeries readMeasurementCsv(std::istream& in, const std::string& source);
MeasurementSeries readMeasurementCsvFile(const std::string& path);
void writeMeasurementCsv(std::ostream& out, const MeasurementSeries& series);

struct RoadSeries {
  std::vector<double> t, left, right;
};
RoadSeries readRoadCsv(std::istream& in, const std::string& source);
RoadSeries readRoadCsvFile(const std::string& path);

}  // namespace pc_ekf
