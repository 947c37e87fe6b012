#include "pc_ekf/pc/sobol_indices.h"

#include <stdexcept>

namespace pc_ekf {

void sobolPartialVariances(const PolynomialBasis& basis, const Eigen::MatrixXd& coefficients,
                           Eigen::MatrixXd* first, Eigen::MatrixXd* total,
                           Eigen::VectorXd* variance) {
  if (coefficients.cols() != basis.size()) {
    throw std::invalid_argument("sobolPartialVariances: " + std::to_string(coefficients.cols()) +
                                " coefficients per output for a basis of " +
                                std::to_string(basis.size()) + " terms");
  }
  const int n = basis.dimension();
  const Eigen::Index outputs = coefficients.rows();
  first->setZero(n, outputs);
  total->setZero(n, outputs);
  variance->setZero(outputs);
  const auto& indices = basis.multiIndices();
  for (int a = 0; a < basis.size(); ++a) {
    int involved = 0, only = -1;
    for (int g = 0; g < n; ++g) {
      if (indices[a][g] > 0) {
        ++involved;
        only = g;
      }
    }
    if (involved == 0) continue;  // the mean
    const Eigen::ArrayXd c2 = coefficients.col(a).array().square();
    *variance += c2.matrix();
    for (int g = 0; g < n; ++g) {
      if (indices[a][g] > 0) total->row(g) += c2.matrix().transpose();
    }
    if (involved == 1) first->row(only) += c2.matrix().transpose();
  }
}

SobolIndices sobolIndices(const PolynomialBasis& basis, const Eigen::VectorXd& coefficients) {
  Eigen::MatrixXd first, total;
  Eigen::VectorXd variance;
  sobolPartialVariances(basis, coefficients.transpose(), &first, &total, &variance);
  SobolIndices s;
  s.variance = variance[0];
  s.first = s.variance > 0 ? Eigen::VectorXd(first.col(0) / s.variance)
                           : Eigen::VectorXd::Zero(basis.dimension());
  s.total = s.variance > 0 ? Eigen::VectorXd(total.col(0) / s.variance)
                           : Eigen::VectorXd::Zero(basis.dimension());
  return s;
}

}  // namespace pc_ekf
