#include "pc_ekf/pc/polynomial_basis.h"

#include <stdexcept>
#include <string>

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

Eigen::MatrixXd PolynomialBasis::evaluate(const Eigen::MatrixXd& points) const {
  Eigen::MatrixXd out(points.rows(), size());
  for (Eigen::Index q = 0; q < points.rows(); ++q) {
    out.row(q) = evaluate(points.row(q).transpose()).transpose();
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
