#include "pc_ekf/filter/measurement.h"

#include <stdexcept>

namespace pc_ekf {

Eigen::VectorXd NoiseModel::variances(const Measurement& m) const {
  const Eigen::ArrayXd relative = (r_relative * m.values.array()).square();
  if (rule == NoiseRule::kPaper) return relative.max(r_floor).matrix();
  Eigen::VectorXd v(m.values.size());
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    const int c = m.channels[static_cast<std::size_t>(i)];
    if (c < 0 || c >= channel_std.size()) throw std::invalid_argument("noise: no sensor std for channel");
    v[i] = channel_std[c] * channel_std[c] + relative[i];
  }
  return v;
}

Eigen::VectorXd NoiseModel::stackedVariances(const std::vector<Measurement>& series) const {
  Eigen::Index rows = 0;
  for (const auto& m : series) rows += m.values.size();
  Eigen::VectorXd out(rows);
  Eigen::Index row = 0;
  for (const auto& m : series) {
    out.segment(row, m.values.size()) = variances(m);
    row += m.values.size();
  }
  return out;
}

MeasurementSeries decimate(const MeasurementSeries& series, int decimation) {
  if (decimation < 1) throw std::invalid_argument("decimation must be >= 1");
  MeasurementSeries out;
  for (std::size_t i = decimation - 1; i < series.size(); i += decimation) out.push_back(series[i]);
  return out;
}

}  // namespace pc_ekf
