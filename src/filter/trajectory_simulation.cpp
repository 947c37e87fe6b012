#include "pc_ekf/filter/trajectory_simulation.h"

#include <algorithm>
#include <stdexcept>

#include "pc_ekf/pc/in_parts.h"

namespace pc_ekf {

namespace {

// Columns integrated together: enough for the vectorised right-hand side, few
// enough that the integrator's stage arrays stay in the first-level caches
// (measured: 1024 columns at once cost twice as much per column as 64).
constexpr Eigen::Index kColumnBlock = 64;

}  // namespace

std::vector<Eigen::MatrixXd> simulateChannels(const MechanicalModel& model,
                                              const Eigen::MatrixXd& params,
                                              const std::vector<double>& times,
                                              const IntegratorSettings& settings) {
  const Eigen::Index channels = model.observationMatrix().rows(), q = params.cols();
  if (q == 0) return std::vector<Eigen::MatrixXd>(times.size(), Eigen::MatrixXd(channels, 0));
  for (std::size_t k = 1; k < times.size(); ++k) {
    if (times[k] < times[k - 1]) {
      throw std::invalid_argument("simulateChannels: sample times must not decrease");
    }
  }
  if (!times.empty() && times.front() < 0.0) {
    throw std::invalid_argument("simulateChannels: sample times must not decrease");
  }
  std::vector<Eigen::MatrixXd> out(times.size(), Eigen::MatrixXd(channels, q));
  // Each column's trajectory does not depend on the others (integrate()), so
  // blocks of columns give the same values as one batch.
  for (Eigen::Index begin = 0; begin < q; begin += kColumnBlock) {
    const Eigen::Index cols = std::min(kColumnBlock, q - begin);
    const auto batch = model.prepare(params.middleCols(begin, cols));
    Eigen::ArrayXXd y = batch->initialState();
    double t = 0.0;
    for (std::size_t k = 0; k < times.size(); ++k) {
      integrate(model, *batch, t, times[k], y, settings);
      t = times[k];
      out[k].middleCols(begin, cols).noalias() = model.observationMatrix() * y.matrix();
    }
  }
  return out;
}

std::vector<Eigen::MatrixXd> simulateChannelsParallel(const MechanicalModel& model,
                                                      const Eigen::MatrixXd& params,
                                                      const std::vector<double>& times,
                                                      const IntegratorSettings& settings,
                                                      int threads) {
  const Eigen::Index q = params.cols();
  threads = static_cast<int>(std::max<Eigen::Index>(1, std::min<Eigen::Index>(threads, q / 8)));
  if (threads <= 1) return simulateChannels(model, params, times, settings);
  std::vector<Eigen::MatrixXd> out(times.size(), Eigen::MatrixXd(model.observationMatrix().rows(), q));
  inNumberedParts(static_cast<int>(q), threads, [&](int, int begin, int end) {
    const std::vector<Eigen::MatrixXd> part =
        simulateChannels(model, params.middleCols(begin, end - begin), times, settings);
    for (std::size_t k = 0; k < times.size(); ++k) out[k].middleCols(begin, end - begin) = part[k];
  });
  return out;
}

bool simulateChannelsWithOffsets(const MechanicalModel& model, const Eigen::MatrixXd& params,
                                 const std::vector<double>& times,
                                 const IntegratorSettings& settings, const Eigen::VectorXd& roll,
                                 const Eigen::VectorXd& lateral, std::vector<Eigen::MatrixXd>* out) {
  const auto batch = model.prepare(params);
  if (!batch->offsetPoints(roll, lateral)) return false;
  out->assign(times.size(), Eigen::MatrixXd(model.observationMatrix().rows(), params.cols()));
  Eigen::ArrayXXd y = batch->initialState();
  double t = 0.0;
  for (std::size_t k = 0; k < times.size(); ++k) {
    integrate(model, *batch, t, times[k], y, settings);
    t = times[k];
    (*out)[k].noalias() = model.observationMatrix() * y.matrix();
  }
  return true;
}

std::vector<double> sampleTimes(const MeasurementSeries& series) {
  std::vector<double> t;
  t.reserve(series.size());
  for (const auto& m : series) t.push_back(m.time);
  return t;
}

}  // namespace pc_ekf
