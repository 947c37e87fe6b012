#include "pc_ekf/pc/basis_truncation.h"

#include <cmath>
#include <stdexcept>

#include "pc_ekf/pc/polynomial_basis.h"

namespace pc_ekf {

std::string toString(TruncationKind k) {
  return k == TruncationKind::kHyperbolic ? "hyperbolic" : "total_degree";
}

TruncationKind truncationKindFromString(const std::string& name) {
  if (name == "total_degree") return TruncationKind::kTotalDegree;
  if (name == "hyperbolic") return TruncationKind::kHyperbolic;
  throw std::invalid_argument("unknown truncation '" + name + "' (total_degree or hyperbolic)");
}

std::vector<std::vector<int>> hyperbolicMultiIndices(int dimension, int order, double q) {
  if (!(q > 0.0 && q <= 1.0)) {
    throw std::invalid_argument("hyperbolicMultiIndices: q-norm " + std::to_string(q) +
                                " outside (0, 1]");
  }
  // sum alpha_i^q <= p^q, with a relative margin so that indices on the
  // boundary (e.g. (1, 1) at q = 0.5, p = 4: 1 + 1 = 2 = 4^0.5) stay whatever
  // pow() rounds to.
  const double bound = std::pow(static_cast<double>(order), q) * (1.0 + 1e-12);
  std::vector<std::vector<int>> kept;
  for (std::vector<int>& alpha : totalDegreeMultiIndices(dimension, order)) {
    double sum = 0.0;
    for (int a : alpha) sum += a == 0 ? 0.0 : std::pow(static_cast<double>(a), q);
    if (sum <= bound) kept.push_back(std::move(alpha));
  }
  return kept;
}

std::vector<std::vector<int>> truncatedMultiIndices(int dimension, int order,
                                                    const BasisTruncation& truncation) {
  std::vector<std::vector<int>> kept =
      truncation.kind == TruncationKind::kTotalDegree
          ? totalDegreeMultiIndices(dimension, order)
          : hyperbolicMultiIndices(dimension, order, truncation.q_norm);
  if (truncation.single_from < 0) return kept;
  std::vector<std::vector<int>> single;
  for (std::vector<int>& alpha : kept) {
    int count = 0;
    for (int i = truncation.single_from; i < dimension; ++i) count += alpha[i] != 0;
    if (count <= 1) single.push_back(std::move(alpha));
  }
  return single;
}

}  // namespace pc_ekf
