// Prior of the reference posterior (docs/method.md §4.6): the product of the germ
// densities, its derivatives for the mode search, and the ranges the grids cover.
#pragma once

#include <Eigen/Dense>
#include <vector>

#include "pc_ekf/pc/germ.h"
#include "pc_ekf/pc/orthonormal_family.h"

namespace pc_ekf {

struct GermInterval {
  double lower = 0.0;
  double upper = 0.0;
  double width() const { return upper - lower; }
};

class PriorDensity {
 public:
  // Throws std::invalid_argument for no germs or an invalid germ shape.
  explicit PriorDensity(const std::vector<GermSpec>& germs);

  int dimension() const { return static_cast<int>(families_.size()); }
  const std::vector<GermSpec>& germs() const { return germs_; }
  // Support of germ i (may be infinite).
  const GermInterval& support(int i) const { return support_[i]; }
  // What a global grid covers: the support, or the 1e-6 .. 1 - 1e-6 quantiles
  // on an infinite side (the mass left out is below the border tolerance).
  const GermInterval& gridRange(int i) const { return range_[i]; }

  // Sum of the log germ densities; -inf outside the closed support, and also
  // where a density is infinite (a boundary point of measure zero, e.g.
  // Beta(0.5, 0.5) at +-1), so grids never produce +inf.
  double logDensity(const Eigen::Ref<const Eigen::VectorXd>& xi) const;
  Eigen::VectorXd logDensities(const Eigen::MatrixXd& xi) const;  // one value per column

  // Gradient of the log density and the non-negative part of its negative
  // (diagonal) second derivative: the prior's share of the Gauss-Newton Hessian.
  void derivatives(const Eigen::Ref<const Eigen::VectorXd>& xi, Eigen::VectorXd& gradient,
                   Eigen::VectorXd& curvature) const;

  // Projects onto the closed support.
  Eigen::VectorXd clamp(const Eigen::Ref<const Eigen::VectorXd>& xi) const;

 private:
  std::vector<GermSpec> germs_;
  std::vector<OrthonormalFamily> families_;
  std::vector<GermInterval> support_, range_;
};

}  // namespace pc_ekf
