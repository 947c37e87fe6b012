// Per-sample parameter PDFs for estimator_node: the histograms of
// pcHistogram (same germ draws, same binning, so the same numbers) with the
// basis evaluated at the draws once, not at every sample (100 000 draws cost
// about 140 ms per parameter to evaluate, the product with new coefficients
// about 1 ms).
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <vector>

#include "pc_ekf/pc/pc_statistics.h"
#include "pc_ekf/pc/polynomial_basis.h"

namespace pc_ekf {

class ParameterPdfSampler {
 public:
  // Draws for parameter i use seed + i, as estimate_offline's final PDFs do.
  ParameterPdfSampler(const PolynomialBasis& basis, int parameters, int draws, int bins,
                      std::uint64_t seed);
  // Histogram of parameter i's expansion (coefficients: the S terms).
  Histogram histogram(int parameter, const Eigen::VectorXd& coefficients) const;

 private:
  std::vector<Eigen::MatrixXd> basis_at_draws_;  // per parameter: draws x S
  int bins_;
};

}  // namespace pc_ekf
