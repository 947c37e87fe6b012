#include "pc_ekf/filter/synthetic_data.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "pc_ekf/filter/trajectory_simulation.h"

namespace pc_ekf {

namespace {

double channelValue(const std::vector<double>& list, int channel, double fallback) {
  return list.empty() ? fallback : list.at(channel);
}

}  // namespace

std::vector<Eigen::MatrixXd> simulateScheduled(const MechanicalModel& model,
                                               const Eigen::VectorXd& params,
                                               const std::vector<ParameterChange>& schedule,
                                               const std::vector<double>& times,
                                               const IntegratorSettings& settings) {
  // Without changes: exactly the common kernel, so the data stay bit-identical.
  if (schedule.empty()) return simulateChannels(model, params, times, settings);
  for (std::size_t k = 0; k < times.size(); ++k) {
    if (times[k] < (k == 0 ? 0.0 : times[k - 1])) {
      throw std::invalid_argument("simulateScheduled: sample times must be >= 0 and not decrease");
    }
  }
  std::vector<Eigen::MatrixXd> out;
  out.reserve(times.size());
  auto batch = model.prepare(params);
  Eigen::ArrayXXd y = batch->initialState();
  double t = 0.0;
  std::size_t next = 0;
  const Eigen::VectorXd* current = &params;
  for (double tk : times) {
    while (next < schedule.size() && schedule[next].time <= tk) {
      const double tc = std::max(t, schedule[next].time);
      integrate(model, *batch, t, tc, y, settings);
      t = tc;
      if (schedule[next].settle) model.carryOver(*current, schedule[next].params, y);
      current = &schedule[next].params;
      batch = model.prepare(*current);
      ++next;
    }
    integrate(model, *batch, t, tk, y, settings);
    t = tk;
    out.push_back(model.observationMatrix() * y.matrix());
  }
  return out;
}

SampleTiming drawSampleTiming(const std::vector<double>& times, const TimingImperfections& p) {
  SampleTiming s{times, times, std::vector<bool>(times.size(), true)};
  if (!p.active()) return s;
  // One generator per feature: turning one on leaves the others' draws alone.
  // (seed_seq keeps 32 bits per value, hence the split.)
  const auto lo = static_cast<std::uint32_t>(p.seed), hi = static_cast<std::uint32_t>(p.seed >> 32);
  std::seed_seq jitter_seed{lo, hi, 1u}, stamp_seed{lo, hi, 2u}, drop_seed{lo, hi, 3u};
  std::mt19937_64 jitter_rng(jitter_seed), stamp_rng(stamp_seed), drop_rng(drop_seed);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (std::size_t k = 0; k < times.size(); ++k) {
    double gap = times[k] - (k == 0 ? 0.0 : times[k - 1]);
    if (k + 1 < times.size()) gap = std::min(gap, times[k + 1] - times[k]);
    const double limit = 0.45 * std::max(gap, 0.0);
    double offset = 0.0;
    if (p.jitter > 0.0) offset = std::clamp(p.jitter * normal(jitter_rng), -limit, limit);
    s.instants[k] = times[k] + offset;
    if (p.stamp_error > 0.0) {
      offset = std::clamp(offset + p.stamp_error * normal(stamp_rng), -limit, limit);
    }
    s.stamps[k] = times[k] + offset;
    if (p.drop_fraction > 0.0) s.kept[k] = uniform(drop_rng) >= p.drop_fraction;
  }
  return s;
}

MeasurementSeries synthesizeMeasurements(const MechanicalModel& model,
                                         const Eigen::VectorXd& truth_params,
                                         const SyntheticDataSettings& s,
                                         MeasurementSeries* clean) {
  std::string why = model.invalidReason(truth_params);
  if (!why.empty()) throw std::invalid_argument("truth parameters invalid: " + why);
  for (const auto& change : s.schedule) {
    why = model.invalidReason(change.params);
    if (!why.empty()) {
      throw std::invalid_argument("truth parameters from t = " + std::to_string(change.time) +
                                  " invalid: " + why);
    }
  }
  const std::size_t nc = static_cast<std::size_t>(model.observationMatrix().rows());
  for (const auto* list : {&s.sensor.noise_floor, &s.sensor.bias, &s.sensor.quantisation,
                           &s.channel_noise_relative}) {
    if (!list->empty() && list->size() != nc) {
      throw std::invalid_argument("sensor imperfections: one value per model channel expected");
    }
  }
  const SampleTiming timing = drawSampleTiming(s.times, s.timing);
  const auto channels =
      simulateScheduled(model, truth_params, s.schedule, timing.instants, s.integration);
  // The IMU's readings from instants imu_clock_offset earlier (a second run).
  std::vector<Eigen::MatrixXd> imu;
  std::vector<bool> is_imu(static_cast<std::size_t>(model.observationMatrix().rows()), false);
  if (s.timing.imu_clock_offset != 0.0) {
    const auto& names = model.channelNames();
    for (std::size_t ch = 0; ch < names.size() && ch < is_imu.size(); ++ch) {
      is_imu[ch] = names[ch].rfind("accel_", 0) == 0 || names[ch].rfind("gyro_", 0) == 0;
    }
    std::vector<double> earlier = timing.instants;
    for (double& t : earlier) t = std::max(0.0, t - s.timing.imu_clock_offset);
    imu = simulateScheduled(model, truth_params, s.schedule, earlier, s.integration);
  }
  int gyro_x = -1;  // the crown's rate goes to it (a cross-fall that changes)
  if (s.cross_fall.active() && s.cross_fall.start != s.cross_fall.end) {
    const auto& names = model.channelNames();
    const auto it = std::find(names.begin(), names.end(), "gyro_x");
    if (it != names.end()) gyro_x = static_cast<int>(it - names.begin());
  }
  std::mt19937_64 rng(s.seed);
  std::normal_distribution<double> normal;
  // Sized once: a long drive's series grown by doubling held up to twice itself.
  const auto kept =
      static_cast<std::size_t>(std::count(timing.kept.begin(), timing.kept.end(), true));
  MeasurementSeries out;
  out.reserve(kept);
  if (clean) {
    clean->clear();
    clean->reserve(kept);
  }
  for (std::size_t k = 0; k < s.times.size(); ++k) {
    if (!timing.kept[k]) continue;
    Measurement m;
    m.time = timing.stamps[k];
    m.channels = s.channels;
    m.values.resize(s.channels.size());
    Measurement exact = m;
    for (std::size_t c = 0; c < s.channels.size(); ++c) {
      const int ch = s.channels[c];
      double z = is_imu[static_cast<std::size_t>(ch)] ? imu[k](ch, 0) : channels[k](ch, 0);
      if (ch == gyro_x) z += s.cross_fall.rate(timing.instants[k]);
      const double floor = channelValue(s.sensor.noise_floor, ch, s.noise_floor);
      const double relative = channelValue(s.channel_noise_relative, ch, s.noise_relative);
      const double sd = std::hypot(relative * z, floor);
      exact.values[c] = z;
      double v = z + sd * normal(rng);
      if (!s.sensor.bias.empty()) v += s.sensor.bias[ch];
      const double step = channelValue(s.sensor.quantisation, ch, 0.0);
      if (step > 0.0) v = step * std::round(v / step);
      m.values[c] = v;
    }
    out.push_back(m);
    if (clean) clean->push_back(exact);
  }
  return out;
}

std::vector<double> uniformSampleTimes(int samples, double duration) {
  std::vector<double> t(samples);
  for (int k = 1; k <= samples; ++k) t[k - 1] = k * duration / samples;
  return t;
}

}  // namespace pc_ekf
