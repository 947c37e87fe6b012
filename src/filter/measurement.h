// Measurements as the estimators consume them: one sample per time, any
// subset of the model's channels (SPEC §1.6).
#pragma once

#include <Eigen/Dense>
#include <vector>

namespace pc_ekf {

struct Measurement {
  double time = 0.0;           // s since the time origin (vehicle at rest at t = 0)
  std::vector<int> channels;   // indices into the model's channelNames(), ascending
  Eigen::VectorXd values;      // one per entry of `channels`
};

using MeasurementSeries = std::vector<Measurement>;

// Filter noise of SPEC §1.6: R_jj = max(r_floor, (r_relative * z_obs,j)^2).
struct NoiseModel {
  double r_relative = 0.01;
  double r_floor = 1e-12;
  Eigen::VectorXd variances(const Eigen::VectorXd& observed) const {
    return (r_relative * observed.array()).square().max(r_floor).matrix();
  }
};

// Every k-th sample (k = decimation), keeping samples k, 2k, ... (1-based).
MeasurementSeries decimate(const MeasurementSeries& series, int decimation);

}  // namespace pc_ekf
