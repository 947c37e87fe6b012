#include "pc_ekf/model/input_noise.h"

#include <algorithm>
#include <cmath>

namespace pc_ekf {

Eigen::MatrixXd inputOutputCovarianceAt(const ReadingInputs& inputs, std::size_t k,
                                        const Eigen::VectorXd& absolute,
                                        const Eigen::VectorXd& relative,
                                        const std::vector<int>& integrated, int outputs,
                                        const ReadingOutputs& evaluate,
                                        Eigen::MatrixXd* slopes) {
  const int n = inputs.count();
  const int m = static_cast<int>(integrated.size());
  std::vector<double> now0(static_cast<std::size_t>(n)), before0(now0.size()), now(now0.size()),
      before(now0.size()), attitude(static_cast<std::size_t>(std::max(m, 1)));
  std::vector<double> plus(static_cast<std::size_t>(outputs)), minus(plus.size());
  Eigen::MatrixXd covariance = Eigen::MatrixXd::Zero(outputs, outputs);
  Eigen::VectorXd d(outputs);
  // Each input's change of the outputs by its noise at k and at k - 1:
  // correlated noise (a blended travel) adds rho (d_now d_before' + its transpose).
  Eigen::MatrixXd now_change = Eigen::MatrixXd::Zero(n, outputs), before_change = now_change;
  const bool at_rest = k == 0;
  const double t = inputs.time(k), t_before = at_rest ? 0.0 : inputs.time(k - 1);
  const double dt = t - t_before;
  inputs.at(t, now0.data());
  std::fill(before0.begin(), before0.end(), 0.0);
  if (!at_rest) inputs.at(t_before, before0.data());
  for (int which = 0; which < 2 * n + m; ++which) {
    const bool angle = which >= 2 * n;
    const int i = angle ? integrated[static_cast<std::size_t>(which - 2 * n)] : which % n;
    if (!angle && which >= n && at_rest) continue;  // nothing read before the first sample
    const double reading = which < n ? now0[i] : before0[i];
    if (angle && inputs.integralInState()) continue;  // the estimator's own state
    const double step = angle ? absolute[i] * std::sqrt(dt * t)
                              : std::hypot(absolute[i], relative[i] * reading);
    if (!(step > 0.0)) continue;
    for (const int sign : {1, -1}) {
      now = now0;
      before = before0;
      std::fill(attitude.begin(), attitude.end(), 0.0);
      if (angle) {
        attitude[static_cast<std::size_t>(which - 2 * n)] = sign * step;
      } else if (which < n) {
        now[static_cast<std::size_t>(i)] += sign * step;
      } else {
        before[static_cast<std::size_t>(i)] += sign * step;
      }
      evaluate(now.data(), before.data(), at_rest, dt, attitude.data(),
               sign > 0 ? plus.data() : minus.data());
    }
    for (int r = 0; r < outputs; ++r) d[r] = 0.5 * (plus[r] - minus[r]);  // derivative times std
    // One noise moves every output: the outputs' errors are correlated.
    covariance.noalias() += d * d.transpose();
    if (!angle) (which < n ? now_change : before_change).row(i) = d.transpose();
  }
  for (int i = 0; i < n && !at_rest; ++i) {
    const double rho = inputs.noiseCorrelation(i);
    if (rho == 0.0) continue;
    const Eigen::MatrixXd cross = now_change.row(i).transpose() * before_change.row(i);
    covariance += rho * (cross + cross.transpose());
  }
  if (slopes) {
    slopes->resize(outputs, 2 * n);
    slopes->leftCols(n) = now_change.transpose();
    slopes->rightCols(n) = before_change.transpose();
  }
  return covariance;
}

Eigen::VectorXd meanVarianceOverSamples(const std::function<Eigen::MatrixXd(std::size_t)>& at,
                                        std::size_t samples, int channels) {
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(channels);
  for (std::size_t k = 0; k < samples; ++k) sum += at(k).diagonal();
  return sum / static_cast<double>(std::max<std::size_t>(samples, 1));
}

double weighedLoad(const ReadingInputs& inputs, int spring_force_sum, double mean_accel_z,
                   double body_mass, double limit, double fallback) {
  if (!(mean_accel_z > 0.0)) return fallback;
  const double force = inputs.sampleSum(spring_force_sum);
  const double load = force / static_cast<double>(inputs.samples()) / mean_accel_z - body_mass;
  return std::isfinite(load) ? std::clamp(load, 0.0, limit) : fallback;
}

}  // namespace pc_ekf
