// The paper's appendix system y' = a y, y(0) = y0: a one-state model used by
// tests to show the filters do not depend on the vehicle. Parameters [a, y0];
// one channel "y".
#pragma once

#include "pc_ekf/model/mechanical_model.h"

namespace pc_ekf {

class ScalarGrowthModel : public MechanicalModel {
 public:
  ScalarGrowthModel(double a, double y0);
  const ModelDescription& description() const override;
  const Eigen::VectorXd& nominalParameters() const override { return nominal_; }
  const Eigen::MatrixXd& observationMatrix() const override { return h_; }
  std::unique_ptr<ModelBatch> prepare(const Eigen::MatrixXd& params) const override;
  std::vector<double> breakpoints(double, double) const override { return {}; }
 private:
  Eigen::VectorXd nominal_;
  Eigen::MatrixXd h_;
};

}  // namespace pc_ekf
