// Nuisance values in the batch methods (ES-MDA, the whole-set update): a
// road's cross-fall and the IMU's biases (docs/method.md §4.12), constant
// over the record, marginalised. To first order they add U n to the
// whitened predictions, n ~ N(0, P) with P = diag(cross_fall^2,
// accel_bias^2, accel_bias^2, gyro_bias^2), so the record's noise
// covariance is I + U P U^T (whitened) instead of I. W = (I + U P U^T)^(-1/2)
// (a rank-4 correction of I) applied to the data and to the forecast makes
// it white again, and the update itself is unchanged.
#pragma once

#include <Eigen/Dense>
#include <vector>

#include "pc_ekf/filter/measurement.h"
#include "pc_ekf/filter/update_safeguards.h"
#include "pc_ekf/model/integrator.h"
#include "pc_ekf/model/mechanical_model.h"

namespace pc_ekf {

// The prior stds (filter.horizon.cross_fall, accel_bias, gyro_bias); all 0: none.
struct BatchNuisance {
  double cross_fall = 0.0;  // rad
  double accel_bias = 0.0;  // m/s^2, accel_y and accel_z
  double gyro_bias = 0.0;   // rad/s
  bool active() const { return cross_fall > 0.0 || accel_bias > 0.0 || gyro_bias > 0.0; }
  static BatchNuisance from(const MovingHorizonSettings& s) {
    return {s.cross_fall, s.accel_bias, s.gyro_bias};
  }
};

// How the nuisance values move each observed entry of `series` (raw channel
// units, stacked sample by sample as the series' channels, one column per
// value: cross-fall per rad, accel_y and accel_z bias per m/s^2, gyro bias
// per rad/s), at the full parameter vector `params`: forward differences of
// the model's roll and lateral offsets (ModelBatch::offsetPoints), the gyro
// bias as a roll that drifts by -b t. Columns whose prior std is 0 are
// dropped. Empty when the model takes no offsets (only the road-free roll
// plane with its IMU does) or nothing is active.
Eigen::MatrixXd nuisanceSensitivity(const MechanicalModel& model, const Eigen::VectorXd& params,
                                    const MeasurementSeries& series,
                                    const IntegratorSettings& integration,
                                    const BatchNuisance& nuisance, Eigen::VectorXd* prior_std);

// W = (I + B B^T)^(-1/2) for B = U diag(prior_std) (rows x k, k small),
// applied in place to the rows of x: x + Q diag((1 + s^2)^(-1/2) - 1) Q^T x
// with B = Q S V^T.
class NuisanceWhitening {
 public:
  NuisanceWhitening() = default;
  NuisanceWhitening(const Eigen::MatrixXd& u, const Eigen::VectorXd& prior_std);
  bool active() const { return q_.cols() > 0; }
  void apply(Eigen::Ref<Eigen::MatrixXd> x) const;
  void apply(Eigen::Ref<Eigen::VectorXd> x) const;
  // The degrees of freedom the nuisance values take from the whitened
  // residual: sum of s^2 / (1 + s^2), E |W r|^2 = rows - absorbed().
  double absorbed() const;

 private:
  Eigen::MatrixXd q_;
  Eigen::VectorXd shrink_;  // (1 + s^2)^(-1/2) - 1
};

}  // namespace pc_ekf
