// Synthetic measurements from the truth model (docs/method.md §1.6): simulate at the
// truth parameters, sample at t_k, add seeded Gaussian noise with standard
// deviation sqrt((relative * z_true)^2 + floor^2).
//
// Optional imperfections make the truth differ from the estimator's model;
// at their defaults the data (values and draw order) are those without them:
// - sensor: per-channel noise floor, constant bias, quantisation;
// - timing: jittered true sampling instants (stamped correctly), an extra
//   stamp error, dropped samples; drawn from their own generator;
// - schedule: the parameters change at given times. The change is
//   quasi-static: the state (deviations from the static equilibrium of the
//   parameters in use) is carried over unchanged and integration goes on with
//   the new parameters, so readings stay deviations from the rest position
//   of the current load.
#pragma once

#include <cstdint>
#include <vector>

#include "pc_ekf/filter/measurement.h"
#include "pc_ekf/model/horizontal_motion.h"
#include "pc_ekf/model/integrator.h"
#include "pc_ekf/model/mechanical_model.h"

namespace pc_ekf {

// Per model channel (index = model channel); an empty list = none.
struct SensorImperfections {
  std::vector<double> noise_floor;   // absolute std; replaces SyntheticDataSettings::noise_floor
  std::vector<double> bias;          // added to the reading
  std::vector<double> quantisation;  // step; reading rounded after noise and bias; 0 = off
};

struct TimingImperfections {
  double jitter = 0.0;         // std (s) of the true instant around t_k
  double stamp_error = 0.0;    // std (s) of the stamp around the true instant
  double drop_fraction = 0.0;  // probability that a sample is lost
  // s: the IMU channels (accel_*, gyro_*) are read this long before their
  // stamp (a clock offset between the IMU and the suspension sensors).
  double imu_clock_offset = 0.0;
  std::uint64_t seed = 1;
  bool active() const { return jitter > 0.0 || stamp_error > 0.0 || drop_fraction > 0.0; }
};

// From `time` on the truth has the full parameter vector `params`.
struct ParameterChange {
  double time = 0.0;
  Eigen::VectorXd params;
  // true: the body stays where it is and settles to the new equilibrium
  // (MechanicalModel::carryOver); false: the state's deviations are kept,
  // so the body jumps to the new equilibrium.
  bool settle = false;
};

struct SyntheticDataSettings {
  std::vector<double> times;
  std::vector<int> channels;  // ascending indices into the model's channels
  double noise_relative = 0.01;
  std::vector<double> channel_noise_relative;  // per model channel (empty: noise_relative)
  double noise_floor = 0.0;
  std::uint64_t seed = 1;
  IntegratorSettings integration;
  SensorImperfections sensor;
  TimingImperfections timing;
  std::vector<ParameterChange> schedule;  // times increasing
  // The road's cross-fall the truth drives on (its lateral share is the
  // truth model's: CrossFallMotion); here its rate d beta / dt is added to a
  // gyro_x channel: the whole vehicle turns with the road's crown.
  CrossFall cross_fall;
};

// `truth_params`: the model's full parameter vector until the first change.
// Also returns the noise-free values when `clean` is given (same stamps).
MeasurementSeries synthesizeMeasurements(const MechanicalModel& model,
                                         const Eigen::VectorXd& truth_params,
                                         const SyntheticDataSettings& settings,
                                         MeasurementSeries* clean = nullptr);

// All channels (channels x 1) at each time, from rest at t = 0, switching the
// parameters at each change as described above. Times must not decrease.
std::vector<Eigen::MatrixXd> simulateScheduled(const MechanicalModel& model,
                                               const Eigen::VectorXd& params,
                                               const std::vector<ParameterChange>& schedule,
                                               const std::vector<double>& times,
                                               const IntegratorSettings& settings);

// The times at which a sample is taken and stamped, and whether it is kept.
struct SampleTiming {
  std::vector<double> instants, stamps;
  std::vector<bool> kept;
};
// Offsets are clipped to +-0.45 of the smaller neighbouring gap (the first
// gap from 0), so instants and stamps stay strictly increasing and > 0.
SampleTiming drawSampleTiming(const std::vector<double>& times, const TimingImperfections& t);

// t_k = k * duration / samples, k = 1..samples.
std::vector<double> uniformSampleTimes(int samples, double duration);

}  // namespace pc_ekf
