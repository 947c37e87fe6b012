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
SparseGridRule smolyakRule(const std::vector<OrthonormalFamily>& families, int level);

// Total-degree exactness of smolyakRule(families, level).
inline int smolyakExactDegree(int level) { return 2 * level + 1; }

}  // namespace pc_ekf
