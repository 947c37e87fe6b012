#include "pc_ekf/pc/sparse_grid.h"

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

SparseGridRule smolyakRule(const std::vector<OrthonormalFamily>& families, int level) {
  const int n = static_cast<int>(families.size());
  if (n < 1) throw std::invalid_argument("smolyakRule: need at least one germ");
  if (level < 0 || level > 30) {
    throw std::invalid_argument("smolyakRule: level must be in 0..30, got " +
                                std::to_string(level));
  }
  // rules[d][l]: the (l + 1)-point Gauss rule of germ d.
  std::vector<std::vector<QuadratureRule>> rules(n);
  for (int d = 0; d < n; ++d) {
    for (int l = 0; l <= level; ++l) rules[d].push_back(families[d].gaussRule(l + 1));
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
      while (d >= 0 && ++idx[d] > l[d]) idx[d--] = 0;
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
