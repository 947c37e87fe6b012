// Collocation points and the least-squares projector onto the basis (docs/method.md §3.4, §3.5).
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <string>

#include "pc_ekf/pc/polynomial_basis.h"

namespace pc_ekf {

enum class PointSequence { kHalton, kHammersley, kGauss };
std::string toString(PointSequence s);
PointSequence pointSequenceFromString(const std::string& name);  // throws std::invalid_argument

class CollocationDesign {
 public:
  // Builds points, A (Q x S) and the projector P (S x Q) with coeffs = P * values,
  // via column-pivoted QR / complete orthogonal decomposition (never normal
  // equations). For kGauss, `count` is the number of nodes per dimension and
  // the projection uses the quadrature weights (exact for degree <= 2n-1-p).
  // Throws std::invalid_argument when Q < S or cond(A) > max_condition, with
  // a message giving Q, S and the condition number.
  CollocationDesign(const PolynomialBasis& basis, PointSequence sequence, int count,
                    std::uint64_t halton_start = 1, double max_condition = 1e8);

  int pointCount() const { return static_cast<int>(points_.rows()); }  // Q
  int termCount() const { return static_cast<int>(design_.cols()); }   // S
  const Eigen::MatrixXd& points() const { return points_; }           // Q x n (germ coordinates)
  const Eigen::MatrixXd& designMatrix() const { return design_; }      // A, Q x S
  const Eigen::MatrixXd& projector() const { return projector_; }      // S x Q
  // cond(A) from its singular values; for kGauss cond(W^(1/2) A), which is 1 when the
  // rule is exact to degree 2p (A alone grows with the tiny tail weights).
  double conditionNumber() const { return condition_; }

  // values: Q x m (one column per projected quantity) -> S x m coefficients.
  Eigen::MatrixXd project(const Eigen::MatrixXd& values) const { return projector_ * values; }
  // coefficients: m x S (row per quantity) -> m x Q values at the points.
  Eigen::MatrixXd evaluateAtPoints(const Eigen::MatrixXd& coefficients) const {
    return coefficients * design_.transpose();
  }

 private:
  Eigen::MatrixXd points_;
  Eigen::MatrixXd design_;
  Eigen::MatrixXd projector_;
  double condition_ = 0.0;
};

}  // namespace pc_ekf
