#include "pc_ekf/health/predictive_check.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

#include "pc_ekf/filter/health.h"
#include "pc_ekf/filter/posterior_residual.h"
#include "pc_ekf/filter/trajectory_simulation.h"

namespace pc_ekf {

PredictiveCheck posteriorPredictiveCheck(const MechanicalModel& model,
                                         const Eigen::VectorXd& params,
                                         const MeasurementSeries& series, const NoiseModel& noise,
                                         const IntegratorSettings& integration, int fitted,
                                         double confidence, const BatchNuisance& nuisance) {
  PredictiveCheck p;
  const int channels = static_cast<int>(model.channelNames().size());
  p.channel_mean = Eigen::VectorXd::Zero(channels);
  Eigen::Index entries = 0;
  for (const auto& m : series) entries += m.values.size();
  if (entries <= fitted) {
    p.problem = "too few observations for the posterior-predictive check";
    return p;
  }
  if (!params.allFinite() || !model.invalidReason(params).empty()) {
    p.problem = "posterior mean outside the model's domain: " +
                (params.allFinite() ? model.invalidReason(params) : std::string("not finite"));
    p.available = true;
    p.outside = true;
    return p;
  }
  const auto sim = simulateChannels(model, params, sampleTimes(series), integration);
  Eigen::VectorXd r = whitenedResiduals(series, noise, sim).col(0);
  int absorbed = 0;  // the nuisance values' share of the residual's dof
  if (nuisance.active()) {
    Eigen::VectorXd stds;
    const Eigen::MatrixXd u =
        nuisanceSensitivity(model, params, series, integration, nuisance, &stds);
    if (u.cols() > 0) {
      // Whitened as the residuals (whitenedResiduals: scaled, then decorrelated).
      Eigen::MatrixXd w = u;
      Eigen::Index row = 0;
      for (const Measurement& m : series) {
        const Eigen::Index k = m.values.size();
        const NoiseWhitening white(noise, m);
        w.middleRows(row, k) = white.variances().cwiseSqrt().cwiseInverse().asDiagonal() *
                               w.middleRows(row, k);
        white.whiten(w.middleRows(row, k));
        row += k;
      }
      const NuisanceWhitening white(w, stds);
      white.apply(Eigen::Ref<Eigen::VectorXd>(r));
      absorbed = static_cast<int>(std::lround(white.absorbed()));
    }
  }
  const Eigen::VectorXd r2 = r.array().square();
  p.available = true;
  p.statistic = r2.sum();
  p.dof = static_cast<int>(entries) - fitted - absorbed;
  const double tail = (1.0 - confidence) / 2.0;
  // Noise that neighbouring samples share (Measurement::serial_variance)
  // leaves T's mean but widens its spread: T taken as s chi2(nu) with the
  // same mean and that variance, s = V / (2 dof), nu = dof / s.
  double serial = 0.0;
  for (const auto& m : series) serial += m.serial_variance;
  // (serial 0: spread 1 exactly, the chi-square's own bounds.)
  if (p.dof > 0) p.spread = 1.0 + serial / (2.0 * p.dof);
  p.lower = p.spread * chiSquareQuantile(tail, p.dof / p.spread);
  p.upper = p.spread * chiSquareQuantile(1.0 - tail, p.dof / p.spread);
  p.outside = !(p.statistic >= p.lower && p.statistic <= p.upper);  // NaN is outside

  // Per channel and per sample, for the warning.
  Eigen::VectorXd count = Eigen::VectorXd::Zero(channels);
  std::vector<double> per_sample(series.size(), 0.0);
  Eigen::Index row = 0;
  for (std::size_t k = 0; k < series.size(); ++k) {
    for (int c : series[k].channels) {
      p.channel_mean[c] += r2[row];
      count[c] += 1.0;
      per_sample[k] += r2[row++];
    }
  }
  for (int c = 0; c < channels; ++c) {
    p.channel_mean[c] = count[c] > 0 ? p.channel_mean[c] / count[c] : 0.0;
    if (count[c] > 0) {
      p.channel_names.push_back(model.channelNames()[static_cast<std::size_t>(c)]);
      p.observed_mean.push_back(p.channel_mean[c]);
    }
  }
  // Worst window: a tenth of the record (at least one sample), by mean contribution.
  const int n = static_cast<int>(series.size());
  const int w = std::max(1, n / 10);
  double best = -1.0, sum = std::accumulate(per_sample.begin(), per_sample.begin() + w, 0.0);
  for (int b = 0; b + w <= n; ++b) {
    if (b > 0) sum += per_sample[b + w - 1] - per_sample[b - 1];
    if (sum > best) {
      best = sum;
      p.worst_window_begin = b;
      p.worst_window_end = b + w;
    }
  }
  p.worst_window_mean = best / w;
  return p;
}

std::string PredictiveCheck::warning(const std::vector<std::string>& names,
                                     const MeasurementSeries& series) const {
  if (!outside) return "";
  std::ostringstream o;
  o.precision(4);
  o << "posterior-predictive check: ";
  if (!problem.empty()) {
    o << problem;
    return o.str();
  }
  o << "normalised residual sum of squares " << statistic << " outside [" << lower << ", "
    << upper << "] (dof " << dof << ")";
  if (statistic < lower) {
    o << ": residuals smaller than R allows (R too large for these sensors?)";
    return o.str();
  }
  std::vector<int> order(channel_mean.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return channel_mean[a] > channel_mean[b]; });
  o << "; worst channels";
  for (std::size_t i = 0; i < order.size() && i < 2; ++i) {
    if (channel_mean[order[i]] <= 0.0) break;
    o << (i ? ", " : " ") << names[order[i]] << " (mean " << channel_mean[order[i]] << " per entry)";
  }
  if (!series.empty()) {
    o << "; worst window t = " << series[worst_window_begin].time << " to "
      << series[worst_window_end - 1].time << " s (mean " << worst_window_mean << " per sample)";
  }
  o << ". The model does not explain the data: declare the vehicle parameters you are unsure "
       "of as uncertain (e.g. spring rates), or check the sensor noise (measurement.r_rule, "
       "sensor_std)";
  return o.str();
}

}  // namespace pc_ekf
