// Smolyak sparse-grid quadrature of a product germ measure, built from each
// germ's own Gauss rules (Smolyak 1963; Gerstner & Griebel 1998).
#pragma once

#include <Eigen/Dense>
#include <vector>

#include "pc_ekf/pc/orthonormal_family.h"

namespace pc_ekf {

// Combination form A(L, n) = sum over L - n + 1 <= |i - 1| <= L of
// (-1)^(L - |i - 1|) C(n - 1, L - |i - 1|) (U^(i_1) x ... x U^(i_n)), with U^(i)
// the i-point Gauss rule of that germ (exact to degree 2i - 1; nodes shared
// between rules, e.g. the centre of symmetric germs, are merged). Exact for
// every polynomial of total degree <= 2 level + 1; with level >= p it projects
// an order-p expansion exactly (products of two basis terms have degree 2p).
// Weights sum to 1 and may be negative. Nodes are rows (Q x n).
struct SparseGridRule {
  Eigen::MatrixXd nodes;
  Eigen::VectorXd weights;
};
// nested = true: a germ whose measure is symmetric on a bounded interval
// (uniform, Beta with alpha = beta) uses nested Clenshaw-Curtis nodes instead
// (level l: the smallest size 1, 3, 5, 9, 17, ... exact to 2l + 1; each size's
// nodes are among the next's, so the grid reuses them) with interpolatory
// weights for the germ's own measure: an m-point rule (m odd, symmetric) is
// exact to degree m >= 2l + 1, so the exactness above holds unchanged. Other
// germs keep their Gauss rules.
SparseGridRule smolyakRule(const std::vector<OrthonormalFamily>& families, int level,
                           bool nested = false);

// The nested rule of `family` at `level` (its nodes, weights summing to 1);
// throws std::invalid_argument when the family has no nested rule here.
QuadratureRule nestedRule(const OrthonormalFamily& family, int level);
bool hasNestedRule(const OrthonormalFamily& family);

// Total-degree exactness of smolyakRule(families, level).
inline int smolyakExactDegree(int level) { return 2 * level + 1; }

}  // namespace pc_ekf
