// Scaffolding for a model given by its description and a per-point
// right-hand side (what a plugin writes): the nominal vector (checked with
// invalidReason), the observation matrix, the road and a batch that calls
// pointDerivatives() for every collocation point. Starts at y = 0 (the
// states are deviations from the static equilibrium). Header-only, so a
// plugin compiles it into its own library.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>

#include "pc_ekf/model/mechanical_model.h"
#include "pc_ekf/model/road_input.h"

namespace pc_ekf {

class PointwiseModel : public MechanicalModel {
 public:
  // Throws std::invalid_argument when the road's contact count is not the
  // description's, or the nominal vector is outside the table's domains.
  PointwiseModel(const ModelDescription& description, Eigen::VectorXd nominal,
                 Eigen::MatrixXd observation, std::shared_ptr<const ContactRoad> road);

  // dydt of one point: p its parameter vector (description order), road the
  // heights under the contacts at t, y and dydt its state (stateSize()).
  virtual void pointDerivatives(double t, const double* p, const double* road, const double* y,
                                double* dydt) const = 0;

  const ModelDescription& description() const override { return description_; }
  const Eigen::VectorXd& nominalParameters() const override { return nominal_; }
  const Eigen::MatrixXd& observationMatrix() const override { return h_; }
  std::unique_ptr<ModelBatch> prepare(const Eigen::MatrixXd& params) const override;
  std::vector<double> breakpoints(double t0, double t1) const override {
    return road_->breakpoints(t0, t1);
  }
  const ContactRoad* contactRoad() const override { return road_.get(); }

 private:
  const ModelDescription& description_;
  Eigen::VectorXd nominal_;
  Eigen::MatrixXd h_;
  std::shared_ptr<const ContactRoad> road_;
};

namespace detail {

class PointwiseBatch : public ModelBatch {
 public:
  PointwiseBatch(const PointwiseModel& m, const Eigen::MatrixXd& p, const ContactRoad& road)
      : m_(m), p_(p), road_(road) {}
  int pointCount() const override { return static_cast<int>(p_.cols()); }
  Eigen::ArrayXXd initialState() const override {
    return Eigen::ArrayXXd::Zero(m_.stateSize(), p_.cols());
  }
  void derivatives(double t, const Eigen::ArrayXXd& y, Eigen::ArrayXXd& dydt) const override {
    Eigen::VectorXd h(road_.contactCount());
    road_.heights(t, h);
    dydt.resize(y.rows(), y.cols());
    for (Eigen::Index q = 0; q < p_.cols(); ++q) {
      m_.pointDerivatives(t, &p_(0, q), h.data(), &y(0, q), &dydt(0, q));
    }
  }

 private:
  const PointwiseModel& m_;
  Eigen::MatrixXd p_;
  const ContactRoad& road_;
};

}  // namespace detail

inline PointwiseModel::PointwiseModel(const ModelDescription& description, Eigen::VectorXd nominal,
                                      Eigen::MatrixXd observation,
                                      std::shared_ptr<const ContactRoad> road)
    : description_(description),
      nominal_(std::move(nominal)),
      h_(std::move(observation)),
      road_(std::move(road)) {
  const std::string& name = description_.name();
  checkModelOnRoad(*this, road_.get(), name);
  if (h_.rows() != static_cast<Eigen::Index>(description_.channelNames().size()) ||
      h_.cols() != stateSize()) {
    throw std::invalid_argument(name + ": observation matrix must be channels x states");
  }
}

inline std::unique_ptr<ModelBatch> PointwiseModel::prepare(const Eigen::MatrixXd& params) const {
  if (params.rows() != nominal_.size()) {
    throw std::invalid_argument(description_.name() + "::prepare: expected " +
                                std::to_string(nominal_.size()) + " parameter rows");
  }
  return std::make_unique<detail::PointwiseBatch>(*this, params, *road_);
}

}  // namespace pc_ekf
