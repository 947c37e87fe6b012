// Multivariate orthonormal basis, total degree or hyperbolic cross (docs/method.md §3.3).
#pragma once

#include <Eigen/Dense>
#include <type_traits>
#include <vector>

#include "pc_ekf/pc/basis_truncation.h"
#include "pc_ekf/pc/germ.h"
#include "pc_ekf/pc/orthonormal_family.h"

namespace pc_ekf {

// Multi-indices of total degree <= order in `dimension` variables, graded:
// ascending total degree; within a degree, reverse lexicographic, i.e. the
// first variable's exponent descending ((1,0) before (0,1); (2,0),(1,1),(0,2)).
// First row is all zeros. Size = C(dimension + order, order).
std::vector<std::vector<int>> totalDegreeMultiIndices(int dimension, int order);

class PolynomialBasis {
 public:
  // Throws std::invalid_argument on empty germs, negative order or a q-norm
  // outside (0, 1].
  PolynomialBasis(std::vector<GermSpec> germs, int order, BasisTruncation truncation = {});
  // An explicit set of multi-indices (each of germs.size() non-negative
  // exponents; the first all zeros, no repeats): an anisotropic basis such as
  // simulated_sensitivity.h chooses. order() is the largest univariate degree.
  // Throws std::invalid_argument naming the first index that breaks a rule.
  PolynomialBasis(std::vector<GermSpec> germs, std::vector<std::vector<int>> indices);

  int dimension() const { return static_cast<int>(germs_.size()); }
  int order() const { return order_; }
  const BasisTruncation& truncation() const { return truncation_; }
  int size() const { return static_cast<int>(indices_.size()); }  // S
  const std::vector<GermSpec>& germs() const { return germs_; }
  const std::vector<std::vector<int>>& multiIndices() const { return indices_; }
  const OrthonormalFamily& family(int d) const { return families_[d]; }

  // psi_1..psi_S at one germ point (length dimension()).
  Eigen::VectorXd evaluate(const Eigen::Ref<const Eigen::VectorXd>& xi) const;
  // Rows = points (Q x dimension) -> Q x S matrix A_qj = psi_j(xi^q).
  Eigen::MatrixXd evaluate(const Eigen::MatrixXd& points) const;
  // Any other Eigen expression: a compile-time column vector is one point, anything
  // else a matrix of points. (Without this, evaluate(VectorXd) is ambiguous between
  // the two overloads above: both need a user-defined conversion.)
  template <typename Derived>
  std::conditional_t<Derived::ColsAtCompileTime == 1, Eigen::VectorXd, Eigen::MatrixXd> evaluate(
      const Eigen::MatrixBase<Derived>& x) const {
    if constexpr (Derived::ColsAtCompileTime == 1) {
      return evaluate(Eigen::Ref<const Eigen::VectorXd>(x));
    } else {
      return evaluate(Eigen::MatrixXd(x));
    }
  }

  // Tensor Gauss rule of the germ measure, `n` nodes per dimension:
  // nodes are rows of a (n^d x d) matrix; weights sum to 1.
  void tensorGaussRule(int n, Eigen::MatrixXd* nodes, Eigen::VectorXd* weights) const;

 private:
  std::vector<GermSpec> germs_;
  int order_;
  BasisTruncation truncation_;
  std::vector<OrthonormalFamily> families_;
  std::vector<std::vector<int>> indices_;
};

}  // namespace pc_ekf
