// A linear test system for the filters: y' = A y + B theta, y(0) = 0,
// z = C y. Its RK4 map is affine in (y, theta), so a first-order Hermite PC
// of Gaussian parameters propagates exactly and the PC filters must equal the
// textbook Kalman filter on the augmented state [y; theta].
#pragma once

#include <memory>

#include "pc_ekf/model/mechanical_model.h"

namespace pc_ekf::testing {

class LinearForcedModel : public MechanicalModel {
 public:
  LinearForcedModel(Eigen::MatrixXd a, Eigen::MatrixXd b, Eigen::MatrixXd c, Eigen::VectorXd nominal)
      : a_(std::move(a)), b_(std::move(b)), c_(std::move(c)), nominal_(std::move(nominal)) {
    ModelDescription::Parts d;
    d.name = "linear_forced";
    std::vector<ParameterSpec> params;
    for (int i = 0; i < a_.rows(); ++i) d.states.push_back("y" + std::to_string(i));
    for (int i = 0; i < b_.cols(); ++i) {
      params.push_back({"theta" + std::to_string(i), "", nominal_[i], anyValue(), ""});
    }
    for (int i = 0; i < c_.rows(); ++i) d.channels.push_back({"z" + std::to_string(i), "", ""});
    d.parameters = ParameterTable(std::move(params));
    description_ = std::make_unique<ModelDescription>(std::move(d));
  }
  const ModelDescription& description() const override { return *description_; }
  const Eigen::VectorXd& nominalParameters() const override { return nominal_; }
  std::string invalidReason(const Eigen::Ref<const Eigen::VectorXd>& p) const override {
    return p.allFinite() ? "" : "non-finite parameter";
  }
  const Eigen::MatrixXd& observationMatrix() const override { return c_; }
  std::vector<double> breakpoints(double, double) const override { return {}; }

  class Batch : public ModelBatch {
   public:
    Batch(const LinearForcedModel& m, const Eigen::MatrixXd& p) : m_(m), forcing_(m.b_ * p) {}
    int pointCount() const override { return static_cast<int>(forcing_.cols()); }
    void derivatives(double, const Eigen::ArrayXXd& y, Eigen::ArrayXXd& dydt) const override {
      dydt = (m_.a_ * y.matrix() + forcing_).array();
    }
    Eigen::ArrayXXd initialState() const override {
      return Eigen::ArrayXXd::Zero(m_.a_.rows(), forcing_.cols());
    }
   private:
    const LinearForcedModel& m_;
    Eigen::MatrixXd forcing_;
  };
  std::unique_ptr<ModelBatch> prepare(const Eigen::MatrixXd& p) const override {
    return std::make_unique<Batch>(*this, p);
  }

 private:
  Eigen::MatrixXd a_, b_, c_;
  Eigen::VectorXd nominal_;
  std::unique_ptr<ModelDescription> description_;
};

}  // namespace pc_ekf::testing
