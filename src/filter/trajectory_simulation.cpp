#include "filter/trajectory_simulation.h"

#include <algorithm>
#include <stdexcept>
#include <thread>

namespace pc_ekf {

std::vector<Eigen::MatrixXd> simulateChannels(const MechanicalModel& model,
                                              const Eigen::MatrixXd& params,
                                              const std::vector<double>& times,
                                              const IntegratorSettings& settings) {
  std::vector<Eigen::MatrixXd> out;
  out.reserve(times.size());
  if (params.cols() == 0) {
    out.assign(times.size(), Eigen::MatrixXd(model.observationMatrix().rows(), 0));
    return out;
  }
  const auto batch = model.prepare(params);
  Eigen::ArrayXXd y = batch->initialState();
  double t = 0.0;
  for (double tk : times) {
    if (tk < t) throw std::invalid_argument("simulateChannels: sample times must not decrease");
    integrate(model, *batch, t, tk, y, settings);
    t = tk;
    out.push_back(model.observationMatrix() * y.matrix());
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
  std::vector<std::vector<Eigen::MatrixXd>> parts(threads);
  std::vector<std::thread> workers;
  std::vector<Eigen::Index> start(threads + 1);
  for (int i = 0; i <= threads; ++i) start[i] = q * i / threads;
  for (int i = 0; i < threads; ++i) {
    workers.emplace_back([&, i] {
      parts[i] = simulateChannels(model, params.middleCols(start[i], start[i + 1] - start[i]),
                                  times, settings);
    });
  }
  for (auto& w : workers) w.join();
  std::vector<Eigen::MatrixXd> out(times.size(), Eigen::MatrixXd(model.observationMatrix().rows(), q));
  for (std::size_t k = 0; k < times.size(); ++k) {
    for (int i = 0; i < threads; ++i) out[k].middleCols(start[i], start[i + 1] - start[i]) = parts[i][k];
  }
  return out;
}

std::vector<double> sampleTimes(const MeasurementSeries& series) {
  std::vector<double> t;
  t.reserve(series.size());
  for (const auto& m : series) t.push_back(m.time);
  return t;
}

}  // namespace pc_ekf
