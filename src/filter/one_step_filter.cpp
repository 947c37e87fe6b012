#include "filter/one_step_filter.h"

#include <stdexcept>

#include "pc/pc_statistics.h"

namespace pc_ekf {

std::string measurementProblem(const Measurement& m, int channel_count) {
  if (!std::isfinite(m.time)) return "non-finite time stamp";
  if (static_cast<Eigen::Index>(m.channels.size()) != m.values.size()) {
    return "channel list and values differ in length";
  }
  for (std::size_t i = 0; i < m.channels.size(); ++i) {
    if (m.channels[i] < 0 || m.channels[i] >= channel_count) return "unknown channel index";
    if (i > 0 && m.channels[i] <= m.channels[i - 1]) return "channels not strictly ascending";
  }
  if (!m.values.allFinite()) return "non-finite measurement value";
  return "";
}

OneStepFilter::OneStepFilter(std::shared_ptr<const PcPropagator> propagator,
                             const OneStepSettings& settings)
    : propagator_(std::move(propagator)),
      settings_(settings),
      health_(*propagator_, settings.health),
      x_(propagator_->priorState()) {}

void OneStepFilter::reset() {
  x_ = propagator_->priorState();
  t_ = 0.0;
  samples_ = 0;
  health_.reset();
}

void OneStepFilter::restore(const Eigen::MatrixXd& x, double time, int samples) {
  if (x.rows() != x_.rows() || x.cols() != x_.cols()) {
    throw std::invalid_argument("restore: state size does not match the filter");
  }
  x_ = x;
  t_ = time;
  samples_ = samples;
  health_.reset();
}

StepResult OneStepFilter::process(const Measurement& m) {
  const MechanicalModel& model = propagator_->model();
  const std::string problem = measurementProblem(m, static_cast<int>(model.channelNames().size()));
  if (!problem.empty()) throw std::invalid_argument("measurement rejected: " + problem);
  if (m.time < t_) throw std::invalid_argument("measurement rejected: time before the filter's");

  StepResult r;
  r.forecast = propagator_->forecast(x_, t_, m.time);
  t_ = m.time;
  r.index = ++samples_;
  r.time = m.time;
  const int ns = propagator_->stateCount();
  if (!m.channels.empty() && r.forecast.ok) {
    // Observation coefficients Z = H X_y of the observed channels.
    z_coeffs_.resize(static_cast<Eigen::Index>(m.channels.size()), x_.cols());
    for (std::size_t i = 0; i < m.channels.size(); ++i) {
      z_coeffs_.row(i).noalias() =
          model.observationMatrix().row(m.channels[i]).lazyProduct(x_.topRows(ns));
    }
    r.update = pcKalmanUpdate(x_, z_coeffs_, m.values, settings_.noise.variances(m.values),
                              settings_.rule);
  } else {
    r.update.finite = x_.allFinite();
  }
  r.coefficients = x_.bottomRows(propagator_->parameterCount());
  r.mean = pcMean(r.coefficients);
  r.stddev = pcStddev(r.coefficients);
  r.health = health_.assess(r.update, r.forecast, r.coefficients);
  return r;
}

}  // namespace pc_ekf
