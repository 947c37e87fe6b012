#include "pc_ekf/io/record_stream.h"

#include "pc_ekf/io/measurement_csv.h"

namespace pc_ekf {
namespace {

class CsvRecordStream : public RecordStream {
 public:
  CsvRecordStream(std::string path, std::vector<std::string> channels)
      : path_(std::move(path)), channels_(std::move(channels)) {}
  bool read(const std::function<void(Measurement&)>& take) override {
    readMeasurementCsvFileRows(path_, channels_, take);
    return true;
  }

 private:
  std::string path_;
  std::vector<std::string> channels_;
};

}  // namespace

std::unique_ptr<RecordStream> csvRecordStream(const std::string& path,
                                              const std::vector<std::string>& channels) {
  return std::make_unique<CsvRecordStream>(path, channels);
}

}  // namespace pc_ekf
