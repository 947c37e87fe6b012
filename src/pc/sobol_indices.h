// Sobol sensitivity indices of a PC expansion (docs/method.md §3): with an
// orthonormal basis the variance is the sum of the squared coefficients
// beyond the mean term, and a germ's share of it is read off the multi-indices
// (Sudret 2008): first order = terms in that germ alone, total = every term
// that involves it.
#pragma once

#include <Eigen/Dense>

#include "pc_ekf/pc/polynomial_basis.h"

namespace pc_ekf {

struct SobolIndices {
  Eigen::VectorXd first, total;  // one per germ, in [0, 1]
  double variance = 0.0;
};

// Partial variances of the outputs (rows of coefficients, outputs x S):
// first(g, o) and total(g, o) = sum of c_o,alpha^2 over the terms alpha of
// germ g alone / involving g; variance(o) = sum over alpha != 0. The indices
// are these over the variance (summing partial variances over outputs or times
// before dividing gives the variance-weighted index of a time series).
void sobolPartialVariances(const PolynomialBasis& basis, const Eigen::MatrixXd& coefficients,
                           Eigen::MatrixXd* first, Eigen::MatrixXd* total,
                           Eigen::VectorXd* variance);

// Indices of one output (coefficients: S); zero where the variance is zero.
SobolIndices sobolIndices(const PolynomialBasis& basis, const Eigen::VectorXd& coefficients);

}  // namespace pc_ekf
