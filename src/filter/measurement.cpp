#include "pc_ekf/filter/measurement.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <stdexcept>

namespace pc_ekf {

Eigen::VectorXd NoiseModel::variances(const Measurement& m) const {
  Eigen::ArrayXd relative = (r_relative * m.values.array()).square();
  if (channel_relative.size() != 0) {
    for (Eigen::Index i = 0; i < relative.size(); ++i) {
      const int c = m.channels[static_cast<std::size_t>(i)];
      if (c < 0 || c >= channel_relative.size()) {
        throw std::invalid_argument("noise: no r_relative for channel");
      }
      relative[i] = (channel_relative[c] * m.values[i]) * (channel_relative[c] * m.values[i]);
    }
  }
  const bool own = m.variances.size() != 0;
  if (own && m.variances.size() != m.values.size()) {
    throw std::invalid_argument("noise: " + std::to_string(m.variances.size()) +
                                " per-sample variances for " + std::to_string(m.values.size()) +
                                " values");
  }
  Eigen::VectorXd v(m.values.size());
  if (rule == NoiseRule::kPaper) {
    v = relative.max(r_floor).matrix();
  } else {
    for (Eigen::Index i = 0; i < v.size(); ++i) {
      const int c = m.channels[static_cast<std::size_t>(i)];
      if (c < 0 || c >= channel_std.size()) throw std::invalid_argument("noise: no sensor std for channel");
      v[i] = channel_std[c] * channel_std[c] + relative[i];
    }
  }
  if (own) {
    for (Eigen::Index i = 0; i < v.size(); ++i) {
      if (std::isfinite(m.variances[i])) v[i] = m.variances[i] + relative[i];
    }
  }
  if (m.extra_covariance.size() != 0) {
    if (m.extra_covariance.rows() != m.values.size() || m.extra_covariance.cols() != m.values.size()) {
      throw std::invalid_argument("noise: a " + std::to_string(m.extra_covariance.rows()) + " x " +
                                  std::to_string(m.extra_covariance.cols()) +
                                  " inherited covariance for " + std::to_string(m.values.size()) +
                                  " values");
    }
    v += m.extra_covariance.diagonal();
  }
  return v;
}

NoiseWhitening::NoiseWhitening(const NoiseModel& noise, const Measurement& m)
    : variances_(noise.variances(m)) {
  const Eigen::Index k = m.values.size();
  if (m.extra_covariance.size() == 0 || k < 2) return;
  Eigen::MatrixXd r = m.extra_covariance;
  r.diagonal().setZero();
  if (r.isZero(0.0)) return;
  r.diagonal() = variances_;
  const Eigen::LLT<Eigen::MatrixXd> llt(r);
  if (llt.info() != Eigen::Success) {
    throw std::invalid_argument("noise: the readings' covariance at t = " + std::to_string(m.time) +
                                " s is not positive definite");
  }
  l_ = llt.matrixL();
  variances_.setOnes();
  active_ = true;
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

Eigen::MatrixXd inputSlopesCovariance(const Eigen::MatrixXd& slopes, const Eigen::VectorXd& rho) {
  const Eigen::Index n = rho.size();
  const Eigen::MatrixXd now = slopes.leftCols(n), before = slopes.rightCols(n);
  const Eigen::MatrixXd cross = now * rho.asDiagonal() * before.transpose();
  return now * now.transpose() + before * before.transpose() + cross + cross.transpose();
}

Measurement onlyChannels(const Measurement& m, const std::vector<int>& keep) {
  Measurement kept;
  kept.time = m.time;
  std::vector<Eigen::Index> rows;
  for (std::size_t i = 0; i < m.channels.size(); ++i) {
    if (std::find(keep.begin(), keep.end(), m.channels[i]) == keep.end()) continue;
    kept.channels.push_back(m.channels[i]);
    rows.push_back(static_cast<Eigen::Index>(i));
  }
  kept.values = m.values(rows);
  if (m.variances.size() != 0) kept.variances = m.variances(rows);
  if (m.extra_covariance.size() != 0) kept.extra_covariance = m.extra_covariance(rows, rows);
  if (m.input_slopes.size() != 0) {
    kept.input_slopes = m.input_slopes(rows, Eigen::all);
    kept.input_correlation = m.input_correlation;
  }
  return kept;
}

MeasurementSeries onlyChannels(const MeasurementSeries& series, const std::vector<int>& keep) {
  MeasurementSeries out;
  out.reserve(series.size());
  for (const Measurement& m : series) out.push_back(onlyChannels(m, keep));
  return out;
}

MeasurementSeries decimate(const MeasurementSeries& series, int decimation) {
  if (decimation < 1) throw std::invalid_argument("decimation must be >= 1");
  MeasurementSeries out;
  for (std::size_t i = decimation - 1; i < series.size(); i += decimation) out.push_back(series[i]);
  return out;
}

}  // namespace pc_ekf
