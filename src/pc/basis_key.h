// A basis's content as a comparable key: process-wide caches of values that
// depend only on the basis (the support draws, the rollover rule) look it up.
#pragma once

#include <tuple>
#include <vector>

#include "pc_ekf/pc/polynomial_basis.h"

namespace pc_ekf {

// Germs (family, alpha, beta), order, multi-indices.
using BasisKey = std::tuple<std::vector<std::tuple<int, double, double>>, int,
                            std::vector<std::vector<int>>>;

inline BasisKey basisKey(const PolynomialBasis& basis) {
  std::vector<std::tuple<int, double, double>> germs;
  for (const GermSpec& g : basis.germs()) germs.emplace_back(static_cast<int>(g.family), g.alpha, g.beta);
  return {std::move(germs), basis.order(), basis.multiIndices()};
}

}  // namespace pc_ekf
