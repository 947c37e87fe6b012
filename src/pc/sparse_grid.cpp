#include "pc_ekf/pc/sparse_grid.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

namespace pc_ekf {

namespace {

double binomial(int n, int k) {
  if (k < 0 || k > n) return 0.0;
  double r = 1.0;
  for (int i = 1; i <= k; ++i) r = r * (n - k + i) / i;
  return r;
}

// Calls f(l) for every l (l_d >= 0 per dimension) with lo <= sum(l) <= hi.
template <typename F>
void forEachLevelVector(std::vector<int>& l, int d, int sum, int lo, int hi, F& f) {
  if (d == static_cast<int>(l.size())) {
    if (sum >= lo) f(l, sum);
    return;
  }
  for (l[d] = 0; sum + l[d] <= hi; ++l[d]) forEachLevelVector(l, d + 1, sum + l[d], lo, hi, f);
  l[d] = 0;
}

}  // namespace

bool hasNestedRule(const OrthonormalFamily& family) {
  const GermSpec& g = family.germ();
  return g.family == GermFamily::kUniform ||
         (g.family == GermFamily::kBeta && g.alpha == g.beta);
}

QuadratureRule nestedRule(const OrthonormalFamily& family, int level) {
  if (!hasNestedRule(family)) {
    throw std::invalid_argument("nestedRule: no nested rule for this germ (needs a symmetric "
                                "measure on [-1, 1])");
  }
  if (level < 0 || level > 30) {
    throw std::invalid_argument("nestedRule: level must be in 0..30, got " +
                                std::to_string(level));
  }
  // Slow growth: the smallest Clenshaw-Curtis size 2^k + 1 exact to 2 level + 1;
  // consecutive levels may share a rule, whose Smolyak differences then vanish.
  int k = 0;
  while ((1 << k) + 1 < 2 * level + 1) ++k;
  const int m = level == 0 ? 1 : (1 << k) + 1;
  QuadratureRule r;
  r.nodes.resize(m);
  // Nodes on the finest grid's angles so that every level yields bit-identical
  // coordinates (the sparse grid merges equal nodes); mirrored for exact symmetry.
  const int fine = 1 << 12, step = m == 1 ? 0 : fine / (m - 1);
  for (int k = 0; k < m; ++k) {
    const int j = k * step;
    r.nodes(k) = m == 1 || 2 * j == fine ? 0.0
                 : 2 * j < fine          ? -std::cos(M_PI * j / fine)
                                         : std::cos(M_PI * (fine - j) / fine);
  }
  // Interpolatory weights: sum_k w_k psi_j(x_k) = delta_j0 for j < m.
  Eigen::MatrixXd psi(m, m);
  for (int k = 0; k < m; ++k) psi.row(k) = family.evaluate(r.nodes(k), m - 1).transpose();
  Eigen::VectorXd e0 = Eigen::VectorXd::Zero(m);
  e0(0) = 1.0;
  r.weights = psi.transpose().fullPivLu().solve(e0);
  return r;
}

SparseGridRule smolyakRule(const std::vector<OrthonormalFamily>& families, int level,
                           bool nested) {
  const int n = static_cast<int>(families.size());
  if (n < 1) throw std::invalid_argument("smolyakRule: need at least one germ");
  if (level < 0 || level > 30) {
    throw std::invalid_argument("smolyakRule: level must be in 0..30, got " +
                                std::to_string(level));
  }
  // rules[d][l]: the (l + 1)-point Gauss rule of germ d, or its nested rule.
  std::vector<std::vector<QuadratureRule>> rules(n);
  for (int d = 0; d < n; ++d) {
    const bool own_nested = nested && hasNestedRule(families[d]);
    for (int l = 0; l <= level; ++l) {
      rules[d].push_back(own_nested ? nestedRule(families[d], l) : families[d].gaussRule(l + 1));
    }
  }
  // Merging by exact coordinates: Golub-Welsch gives the symmetric centre as
  // a tiny nonzero number, so snap |x| < 1e-14 to 0 before comparing.
  std::map<std::vector<double>, double> merged;
  std::vector<double> key(n);
  auto add_tensor_rule = [&](const std::vector<int>& l, int sum) {
    const double coefficient = ((level - sum) % 2 == 0 ? 1.0 : -1.0) * binomial(n - 1, level - sum);
    if (coefficient == 0.0) return;
    std::vector<int> idx(n, 0);
    while (true) {
      double w = coefficient;
      for (int d = 0; d < n; ++d) {
        const double x = rules[d][l[d]].nodes(idx[d]);
        key[d] = std::abs(x) < 1e-14 ? 0.0 : x;
        w *= rules[d][l[d]].weights(idx[d]);
      }
      merged[key] += w;
      int d = n - 1;
      while (d >= 0 && ++idx[d] >= rules[d][l[d]].nodes.size()) idx[d--] = 0;
      if (d < 0) break;
    }
  };
  std::vector<int> l(n, 0);
  forEachLevelVector(l, 0, 0, std::max(0, level - n + 1), level, add_tensor_rule);
  SparseGridRule rule;
  rule.nodes.resize(static_cast<Eigen::Index>(merged.size()), n);
  rule.weights.resize(static_cast<Eigen::Index>(merged.size()));
  Eigen::Index r = 0;
  for (const auto& [x, w] : merged) {
    for (int d = 0; d < n; ++d) rule.nodes(r, d) = x[d];
    rule.weights(r++) = w;
  }
  return rule;
}

}  // namespace pc_ekf
