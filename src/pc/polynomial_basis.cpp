#include "pc_ekf/pc/polynomial_basis.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace pc_ekf {
namespace {

// Appends all exponent vectors of `remaining` variables summing to `degree`,
// the current variable's exponent descending (the graded order of the header).
void appendCompositions(int degree, int remaining, std::vector<int>* prefix,
                        std::vector<std::vector<int>>* out) {
  if (remaining == 1) {
    prefix->push_back(degree);
    out->push_back(*prefix);
    prefix->pop_back();
    return;
  }
  for (int e = degree; e >= 0; --e) {
    prefix->push_back(e);
    appendCompositions(degree - e, remaining - 1, prefix, out);
    prefix->pop_back();
  }
}

}  // namespace

std::vector<std::vector<int>> totalDegreeMultiIndices(int dimension, int order) {
  if (dimension < 1 || order < 0) {
    throw std::invalid_argument("totalDegreeMultiIndices: need dimension >= 1 and order >= 0");
  }
  std::vector<std::vector<int>> indices;
  std::vector<int> prefix;
  for (int degree = 0; degree <= order; ++degree) {
    appendCompositions(degree, dimension, &prefix, &indices);
  }
  return indices;
}

PolynomialBasis::PolynomialBasis(std::vector<GermSpec> germs, int order, BasisTruncation truncation)
    : germs_(std::move(germs)), order_(order), truncation_(truncation) {
  if (germs_.empty()) throw std::invalid_argument("PolynomialBasis: no germs");
  if (order_ < 0) {
    throw std::invalid_argument("PolynomialBasis: negative order " + std::to_string(order_));
  }
  families_.reserve(germs_.size());
  for (const GermSpec& g : germs_) families_.emplace_back(g);
  indices_ = truncatedMultiIndices(dimension(), order_, truncation_);
}

PolynomialBasis::PolynomialBasis(std::vector<GermSpec> germs, std::vector<std::vector<int>> indices)
    : germs_(std::move(germs)), order_(0), indices_(std::move(indices)) {
  if (germs_.empty()) throw std::invalid_argument("PolynomialBasis: no germs");
  if (indices_.empty()) throw std::invalid_argument("PolynomialBasis: no multi-indices");
  std::set<std::vector<int>> seen;
  for (std::size_t j = 0; j < indices_.size(); ++j) {
    const auto& a = indices_[j];
    const bool zero = std::all_of(a.begin(), a.end(), [](int e) { return e == 0; });
    if (a.size() != germs_.size() || (j == 0) != zero ||
        std::any_of(a.begin(), a.end(), [](int e) { return e < 0; }) || !seen.insert(a).second) {
      throw std::invalid_argument(
          "PolynomialBasis: multi-index " + std::to_string(j) +
          " must have one non-negative exponent per germ (" + std::to_string(germs_.size()) +
          "), be all zeros exactly when it is the first, and not repeat");
    }
    order_ = std::max(order_, *std::max_element(a.begin(), a.end()));
  }
  families_.reserve(germs_.size());
  for (const GermSpec& g : germs_) families_.emplace_back(g);
}

Eigen::VectorXd PolynomialBasis::evaluate(const Eigen::Ref<const Eigen::VectorXd>& xi) const {
  if (xi.size() != dimension()) {
    throw std::invalid_argument("PolynomialBasis::evaluate: point has " +
                                std::to_string(xi.size()) + " coordinates, expected " +
                                std::to_string(dimension()));
  }
  // Univariate values per dimension: column d holds psi_0..psi_p of xi_d.
  Eigen::MatrixXd univariate(order_ + 1, dimension());
  for (int d = 0; d < dimension(); ++d) {
    families_[d].evaluate(xi(d), order_, univariate.col(d).data());
  }
  Eigen::VectorXd out(size());
  for (int j = 0; j < size(); ++j) {
    double value = 1.0;
    for (int d = 0; d < dimension(); ++d) value *= univariate(indices_[j][d], d);
    out(j) = value;
  }
  return out;
}

// The point-by-point evaluate()'s numbers, bit for bit, without its two
// allocations per point: the recurrence with its constants taken out of the
// loop (OrthonormalFamily::evaluate's operations in its order), and each term
// the product of its factors of degree > 0 in ascending d (the factors
// psi_0 = 1 it multiplies by are exact).
Eigen::MatrixXd PolynomialBasis::evaluate(const Eigen::MatrixXd& points) const {
  if (points.cols() != dimension()) {
    throw std::invalid_argument("PolynomialBasis::evaluate: point has " +
                                std::to_string(points.cols()) + " coordinates, expected " +
                                std::to_string(dimension()));
  }
  const Eigen::Index rows = points.rows();
  const int n = dimension(), p = order_;
  // univariate(q, d * p + k - 1) = psi_k(points(q, d)), k = 1..p.
  Eigen::MatrixXd univariate(rows, static_cast<Eigen::Index>(n) * p);
  for (int d = 0; d < n && p >= 1; ++d) {
    const OrthonormalFamily& f = families_[d];
    std::vector<double> a(p), sqrt_b(p + 1);
    for (int k = 0; k < p; ++k) a[k] = f.recurrenceA(k);
    for (int k = 1; k <= p; ++k) sqrt_b[k] = std::sqrt(f.recurrenceB(k));
    for (Eigen::Index q = 0; q < rows; ++q) {
      const double x = points(q, d);
      double before = 1.0, current = (x - a[0]) / sqrt_b[1];
      univariate(q, d * p) = current;
      for (int k = 1; k < p; ++k) {
        const double next = ((x - a[k]) * current - sqrt_b[k] * before) / sqrt_b[k + 1];
        univariate(q, d * p + k) = next;
        before = current;
        current = next;
      }
    }
  }
  Eigen::MatrixXd out(rows, size());
  std::vector<Eigen::Index> factors;
  for (int j = 0; j < size(); ++j) {
    factors.clear();
    for (int d = 0; d < n; ++d) {
      if (indices_[j][d] > 0) factors.push_back(static_cast<Eigen::Index>(d) * p + indices_[j][d] - 1);
    }
    if (factors.empty()) {
      out.col(j).setOnes();
      continue;
    }
    out.col(j) = univariate.col(factors[0]);
    for (std::size_t m = 1; m < factors.size(); ++m) out.col(j).array() *= univariate.col(factors[m]).array();
  }
  return out;
}

void PolynomialBasis::tensorGaussRule(int n, Eigen::MatrixXd* nodes,
                                      Eigen::VectorXd* weights) const {
  if (n < 1) throw std::invalid_argument("tensorGaussRule: need at least one node per dimension");
  std::vector<QuadratureRule> rules;
  long total = 1;
  for (const OrthonormalFamily& f : families_) {
    rules.push_back(f.gaussRule(n));
    total *= n;
  }
  nodes->resize(total, dimension());
  weights->resize(total);
  // Row r enumerates the node tuple in mixed radix n, last dimension fastest.
  for (long r = 0; r < total; ++r) {
    long rest = r;
    double w = 1.0;
    for (int d = dimension() - 1; d >= 0; --d) {
      const int i = static_cast<int>(rest % n);
      rest /= n;
      (*nodes)(r, d) = rules[d].nodes(i);
      w *= rules[d].weights(i);
    }
    (*weights)(r) = w;
  }
}

}  // namespace pc_ekf
