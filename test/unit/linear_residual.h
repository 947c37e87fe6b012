// A Gaussian likelihood in germ coordinates for the posterior references'
// tests: r = L^-1 (xi - mu), so the likelihood is N(mu, L L^T). With
// `counted` it reports its evaluations as simulations (else 0, as a residual
// without a model).
#pragma once

#include "pc_ekf/filter/posterior_residual.h"

namespace pc_ekf::testing {

class LinearResidual : public PosteriorResidual {
 public:
  LinearResidual(Eigen::VectorXd mu, Eigen::MatrixXd chol, bool counted = false)
      : mu_(std::move(mu)), l_(std::move(chol)), counted_(counted) {}
  int dimension() const override { return static_cast<int>(mu_.size()); }
  Eigen::MatrixXd residuals(const Eigen::MatrixXd& xi) const override {
    evaluations_ += xi.cols();
    return l_.triangularView<Eigen::Lower>().solve(xi.colwise() - mu_);
  }
  long simulations() const override { return counted_ ? evaluations_ : 0; }

 private:
  Eigen::VectorXd mu_;
  Eigen::MatrixXd l_;
  bool counted_;
  mutable long evaluations_ = 0;
};

}  // namespace pc_ekf::testing
