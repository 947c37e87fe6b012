// The roll plane without a road (docs/method.md §4.10): the body is driven by
// the suspension forces computed from the measured travel and rate (inputs),
// and the IMU sees how it answers. Road, tyres and unsprung masses drop out.
//
// Inputs (ReadingInputs, in this order): u1 u2 v1 v2, then gyro_x when the
// record has it, then speed and gyro_z when it has them (a_y = speed gyro_z).
// Outputs, kept as reading states: accel_y, accel_z, gyro_x. Heights, the
// anti-roll bar and a_y as in the model on a road (docs/models.md): the bar's
// force from the travels, the elevated masses' S a_y and S (g + a_P) sin(phi)
// moments, and the IMU's a_y and z_I terms.
//   F_i = F_K(delta_ref,i - u_i) - F_C(v_i), delta_ref the spring's compression
//     at the zero of the readings (tare: the empty vehicle; rest: the loaded);
//   g + a_cg = (F_1 + F_2) / (m + M);
//   theta'' = cos(phi) (-D F_1 + (L - D) F_2) / I_cg, phi'' = -theta'';
//   at the IMU: g + a = g + a_cg + (s - D) theta'';
//   phi = phi_s + (integral of the measured gyro from 0): accel_y = (g + a) sin phi,
//   accel_z = (g + a) cos phi (rest: minus g sin phi_s, g cos phi_s);
//   gyro_x at t_k = the measured gyro at the previous sample t_{k-1} plus the
//     trapezoid of phi'' over [t_{k-1}, t_k] (the increment: no drift).
// Per point, ModelBatch::offsetPoints adds a roll offset to phi (the
// estimator's angle error and gyro bias drift) and a lateral specific force
// to a_y (a road's cross-fall beta: g sin(beta); docs/method.md §4.12).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "pc_ekf/model/reading_inputs.h"
#include "pc_ekf/model/roll_plane_model.h"

namespace pc_ekf {

struct RoadFreeConstants;

class RollPlaneRoadFreeModel : public MechanicalModel {
 public:
  // Throws std::invalid_argument when the inputs are not u1 u2 v1 v2
  // [gyro_x] or the nominal parameters are invalid.
  RollPlaneRoadFreeModel(const VehicleParameters& nominal,
                         std::shared_ptr<const ReadingInputs> inputs, ZeroConvention zero);

  const ModelDescription& description() const override { return rollPlaneDescription(); }
  const Eigen::VectorXd& nominalParameters() const override { return nominal_vector_; }
  std::string invalidReason(const Eigen::Ref<const Eigen::VectorXd>& params) const override {
    return with_road_.invalidReason(params);
  }
  const std::vector<std::string>& stateNames() const override { return state_names_; }
  int readingCount() const override { return 3; }
  bool channelModelled(int channel) const override;
  bool channelIsInput(int channel) const override;
  ZeroConvention zero() const override { return zero_; }
  const Eigen::MatrixXd& observationMatrix() const override { return h_; }
  std::unique_ptr<ModelBatch> prepare(const Eigen::MatrixXd& params) const override;
  std::vector<double> breakpoints(double, double) const override { return {}; }

  // Per model channel: the variance an output inherits from the inputs'
  // noise (errors in variables), to first order, averaged over the record's
  // samples. An input's noise std at a sample is hypot(absolute, relative *
  // reading) (one entry per input, in the inputs' order). The derivatives
  // are taken at the nominal vehicle; with tare and mean_accel_z > 0 (the
  // record's mean accel_z) at the load the record weighs: the springs' mean
  // force over mean_accel_z, less the body mass.
  SampleInputNoise inputNoiseBySample(const Eigen::VectorXd& absolute,
                                      const Eigen::VectorXd& relative,
                                      double mean_accel_z) const override;
  Eigen::VectorXd inputNoiseVariance(const Eigen::VectorXd& absolute,
                                     const Eigen::VectorXd& relative,
                                     double mean_accel_z) const override;
  const ReadingInputs& inputs() const { return *inputs_; }
  int inputCount() const override { return inputs_->count(); }

  // Tyre loads from the readings at t: on each side the suspension's force
  // (the spring at the compression delta_ref - u_i, its static part the
  // side's weight share at the static equilibrium of `params`, minus the
  // damper's force at v_i, plus the anti-roll bar's k_a (x_1 - x_2)), plus
  // the side's unsprung weight m_u,i g; side 1 (the left end) is the left.
  // With a_y read (speed x gyro_z), the lateral forces that reach the tyres
  // without the springs move a_y ((m + M) h_P + sum m_u r_w) / L from the
  // left tyre to the right (a_y > 0: a left turn).
  // NaN when `params` is not admissible or the equilibrium fails.
  bool hasLoadTransferRatio() const override { return true; }
  double loadTransferRatio(const Eigen::VectorXd& params, double t) const override;

 private:
  std::unique_ptr<RoadFreeConstants> constants(const Eigen::MatrixXd& params) const;

  VehicleParameters nominal_;
  RollPlaneModel with_road_;  // the same vehicle's checks
  std::shared_ptr<const ReadingInputs> inputs_;
  ZeroConvention zero_;
  Eigen::VectorXd nominal_vector_;
  std::vector<std::string> state_names_;
  Eigen::MatrixXd h_;
  int spring_force_sum_ = -1;  // tare: ReadingInputs::sampleSum's handle
  int gyro_ = -1, speed_ = -1, yaw_ = -1;  // the optional inputs' places (-1: not read)
  static constexpr int kGyroChannel = 6, kSpeedChannel = 7, kYawChannel = 8;
};

}  // namespace pc_ekf
