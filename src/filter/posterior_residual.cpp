#include "pc_ekf/filter/posterior_residual.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "pc_ekf/filter/trajectory_simulation.h"

namespace pc_ekf {

Eigen::VectorXd logLikelihood(const Eigen::MatrixXd& residuals) {
  Eigen::VectorXd out(residuals.cols());
  for (Eigen::Index j = 0; j < residuals.cols(); ++j) {
    const double s = residuals.col(j).squaredNorm();
    out[j] = std::isfinite(s) ? -0.5 * s : -std::numeric_limits<double>::infinity();
  }
  return out;
}

Eigen::MatrixXd whitenedResiduals(const MeasurementSeries& series, const NoiseModel& noise,
                                  const std::vector<Eigen::MatrixXd>& channels) {
  if (channels.size() != series.size()) {
    throw std::invalid_argument("whitenedResiduals: " + std::to_string(channels.size()) +
                                " channel blocks for " + std::to_string(series.size()) +
                                " samples");
  }
  Eigen::Index rows = 0;
  for (const Measurement& m : series) rows += m.values.size();
  const Eigen::Index b = channels.empty() ? 0 : channels.front().cols();
  Eigen::MatrixXd r(rows, b);
  Eigen::Index row = 0;
  for (std::size_t k = 0; k < series.size(); ++k) {
    const Measurement& m = series[k];
    const NoiseWhitening white(noise, m);
    const Eigen::VectorXd scale = white.variances().cwiseSqrt().cwiseInverse();
    const Eigen::Index first = row;
    for (std::size_t c = 0; c < m.channels.size(); ++c, ++row) {
      const int ch = m.channels[c];
      if (ch < 0 || ch >= channels[k].rows()) {
        throw std::invalid_argument("whitenedResiduals: channel index " + std::to_string(ch) +
                                    " out of range");
      }
      r.row(row) = scale[c] * (m.values[c] - channels[k].row(ch).array());
    }
    white.whiten(r.middleRows(first, row - first));
  }
  return r;
}

std::vector<Eigen::MatrixXd> simulateGermChannels(const MechanicalModel& model,
                                                  const ParameterMapping& mapping,
                                                  const Eigen::MatrixXd& xi,
                                                  const std::vector<double>& times,
                                                  const IntegratorSettings& integration,
                                                  int threads, long* simulations) {
  const Eigen::Index b = xi.cols();
  const Eigen::MatrixXd full = mapping.fullParameters(mapping.valuesAtGerms(xi.transpose()));
  std::vector<Eigen::Index> valid;
  valid.reserve(b);
  for (Eigen::Index j = 0; j < b; ++j) {
    if (xi.col(j).allFinite() && model.invalidReason(full.col(j)).empty()) valid.push_back(j);
  }
  const Eigen::Index channels = model.observationMatrix().rows();
  std::vector<Eigen::MatrixXd> out(
      times.size(),
      Eigen::MatrixXd::Constant(channels, b, std::numeric_limits<double>::quiet_NaN()));
  if (valid.empty()) return out;
  Eigen::MatrixXd params(full.rows(), static_cast<Eigen::Index>(valid.size()));
  for (std::size_t i = 0; i < valid.size(); ++i) params.col(i) = full.col(valid[i]);
  const std::vector<Eigen::MatrixXd> sim =
      simulateChannelsParallel(model, params, times, integration, threads);
  for (std::size_t k = 0; k < times.size(); ++k) {
    for (std::size_t i = 0; i < valid.size(); ++i) out[k].col(valid[i]) = sim[k].col(i);
  }
  if (simulations != nullptr) *simulations += static_cast<long>(valid.size());
  return out;
}

ModelPosteriorResidual::ModelPosteriorResidual(const MechanicalModel& model,
                                               const ParameterMapping& mapping,
                                               MeasurementSeries series, const NoiseModel& noise,
                                               const IntegratorSettings& integration, int threads)
    : model_(model),
      mapping_(mapping),
      series_(std::move(series)),
      noise_(noise),
      integration_(integration),
      threads_(threads),
      times_(sampleTimes(series_)) {
  if (series_.empty()) throw std::invalid_argument("ModelPosteriorResidual: empty series");
  for (const Measurement& m : series_) {
    if (!m.values.allFinite() || m.values.size() != static_cast<Eigen::Index>(m.channels.size())) {
      throw std::invalid_argument(
          "ModelPosteriorResidual: sample at t = " + std::to_string(m.time) +
          " has non-finite values or mismatched channels");
    }
  }
}

Eigen::MatrixXd ModelPosteriorResidual::residuals(const Eigen::MatrixXd& xi) const {
  if (xi.rows() != dimension()) {
    throw std::invalid_argument("ModelPosteriorResidual: xi has " + std::to_string(xi.rows()) +
                                " rows, expected " + std::to_string(dimension()));
  }
  long count = 0;
  const auto channels =
      simulateGermChannels(model_, mapping_, xi, times_, integration_, threads_, &count);
  simulations_ += count;
  return whitenedResiduals(series_, noise_, channels);
}

}  // namespace pc_ekf
