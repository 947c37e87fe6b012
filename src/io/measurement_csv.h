// The measurement and road CSV formats:
//   measurements: header t, then the model's channels (roll plane t,u1,u2,v1,v2);
//                 empty cell or nan = not observed
//   road:         header t, then the model's road columns (roll plane t,y1,y2)
// SI units, one sample a row, time strictly increasing.
#pragma once

#include <functional>
#include <istream>
#include <stdexcept>
#include <string>
#include <vector>

#include "pc_ekf/filter/measurement.h"
#include "pc_ekf/model/roll_plane_model.h"  // rollPlaneChannels(): the default channels

namespace pc_ekf {

// Names the file, the line and what was expected.
class CsvError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// `channels`: the model's channel names (column c+1 = channel c).
MeasurementSeries readMeasurementCsv(std::istream& in, const std::string& source,
                                     const std::vector<std::string>& channels = rollPlaneChannels());
MeasurementSeries readMeasurementCsvFile(
    const std::string& path, const std::vector<std::string>& channels = rollPlaneChannels());
// The file's samples one at a time to `take`, line by line (the same
// samples and errors as readMeasurementCsvFile's, none held).
void readMeasurementCsvFileRows(const std::string& path, const std::vector<std::string>& channels,
                                const std::function<void(Measurement&)>& take);
void writeMeasurementCsv(std::ostream& out, const MeasurementSeries& series,
                         const std::vector<std::string>& channels = rollPlaneChannels());

// A road of any number of contacts: times and one column per contact.
struct ContactSeries {
  std::vector<double> t;
  std::vector<std::vector<double>> heights;  // [contact][sample]
};
// `columns`: the model's road columns (ModelType::roadColumns()), after t.
ContactSeries readContactRoadCsv(std::istream& in, const std::string& source,
                                 const std::vector<std::string>& columns);
ContactSeries readContactRoadCsvFile(const std::string& path, const std::vector<std::string>& columns);

}  // namespace pc_ekf
