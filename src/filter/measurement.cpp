#include "filter/measurement.h"

#include <stdexcept>

namespace pc_ekf {

MeasurementSeries decimate(const MeasurementSeries& series, int decimation) {
  if (decimation < 1) throw std::invalid_argument("decimation must be >= 1");
  MeasurementSeries out;
  for (std::size_t i = decimation - 1; i < series.size(); i += decimation) out.push_back(series[i]);
  return out;
}

}  // namespace pc_ekf
