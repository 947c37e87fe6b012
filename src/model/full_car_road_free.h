// The full car without a road (docs/method.md §4.10): the body (heave, pitch,
// roll) driven by the four suspension forces computed from the measured travel
// and rate; the IMU channels are the outputs.
//
// Inputs (ReadingInputs, in this order): u_fl u_fr u_rl u_rr v_fl v_fr v_rl
// v_rr, then gyro_x gyro_y when the record has them, speed gyro_z (a_y =
// speed x gyro_z) and accel_x (a_x = accel_x - (g + z'') theta + z_I theta''
// + imu_x theta'^2) when it has them (without accel_x, a_x = 0). Outputs, kept
// as reading states: accel_y, accel_z, gyro_x, gyro_y. Heights, bars and
// a_x, a_y as in the model on a road (docs/models.md), with the total forces;
// all 0 and none of the optional motion inputs: the equations below, bit for bit.
//   F_i = F_K(delta_ref,i - u_i) - F_C(v_i)  (delta_ref: tare the empty vehicle's,
//     rest the loaded one's static compression);
//   M_b q'' = sum_i F_i [1, x_i, y_i] - [(m_s + M) g, M x_M g, M y_M g], q = (z, theta, phi);
//   g + a = g + z'' + imu_x theta'' + imu_y phi'' at the IMU;
//   roll = phi_s + integral of gyro_x, pitch (nose down) = -theta_s + integral of gyro_y;
//   accel_y = (g + a) cos(pitch) sin(roll), accel_z = (g + a) cos(pitch) cos(roll);
//   gyro_x, gyro_y at t_k: the reading at t_{k-1} plus the trapezoid of phi''
//     (resp. -theta'') over [t_{k-1}, t_k].
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "pc_ekf/model/full_car_model.h"
#include "pc_ekf/model/reading_inputs.h"

namespace pc_ekf {

struct FullCarRoadFreeConstants;

class FullCarRoadFreeModel : public MechanicalModel {
 public:
  // Throws std::invalid_argument for other inputs or invalid nominal values.
  FullCarRoadFreeModel(const FullCarParameters& nominal,
                       std::shared_ptr<const ReadingInputs> inputs, ZeroConvention zero);
  ~FullCarRoadFreeModel() override;

  const ModelDescription& description() const override { return fullCarDescription(); }
  const Eigen::VectorXd& nominalParameters() const override { return nominal_vector_; }
  std::string invalidReason(const Eigen::Ref<const Eigen::VectorXd>& params) const override {
    return with_road_.invalidReason(params);
  }
  const std::vector<std::string>& stateNames() const override { return state_names_; }
  int readingCount() const override { return 4; }
  bool channelModelled(int channel) const override;
  bool channelIsInput(int channel) const override;
  ZeroConvention zero() const override { return zero_; }
  const Eigen::MatrixXd& observationMatrix() const override { return h_; }
  std::unique_ptr<ModelBatch> prepare(const Eigen::MatrixXd& params) const override;
  std::vector<double> breakpoints(double, double) const override { return {}; }

  // As RollPlaneRoadFreeModel::inputNoiseVariance (per model channel).
  SampleInputNoise inputNoiseBySample(const Eigen::VectorXd& absolute,
                                      const Eigen::VectorXd& relative,
                                      double mean_accel_z) const override;
  int inputCount() const override { return inputs_->count(); }
  Eigen::VectorXd inputNoiseVariance(const Eigen::VectorXd& absolute,
                                     const Eigen::VectorXd& relative,
                                     double mean_accel_z) const override;

 private:
  std::unique_ptr<FullCarRoadFreeConstants> constants(const Eigen::MatrixXd& params) const;

  FullCarParameters nominal_;
  FullCarModel with_road_;  // the same vehicle's checks and equilibrium
  std::shared_ptr<const ReadingInputs> inputs_;
  ZeroConvention zero_;
  Eigen::VectorXd nominal_vector_;
  std::vector<std::string> state_names_;
  Eigen::MatrixXd h_;
  int spring_force_sum_ = -1;  // tare: ReadingInputs::sampleSum's handle
  // The optional inputs' places (-1: not read).
  int gyro_x_ = -1, gyro_y_ = -1, speed_ = -1, yaw_ = -1, accel_x_ = -1;
  static constexpr int kAccelXChannel = 12, kSpeedChannel = 13, kYawChannel = 14;
};

}  // namespace pc_ekf
