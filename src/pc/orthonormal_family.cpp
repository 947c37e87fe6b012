#include "pc_ekf/pc/orthonormal_family.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "pc_ekf/pc/special_functions.h"

namespace pc_ekf {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

bool isBeta22(const GermSpec& g) {
  return g.family == GermFamily::kBeta && g.alpha == 2.0 && g.beta == 2.0;
}

// Monic Jacobi recurrence for the weight (1 - x)^a (1 + x)^b, normalised to a
// probability measure (b_0 = 1). The general formulas are 0/0 at n = 0 when
// a + b = 0 and at n = 1 when a + b = -1, hence the explicit low-order cases.
double jacobiA(double a, double b, int n) {
  if (n == 0) return (b - a) / (a + b + 2.0);
  const double s = 2.0 * n + a + b;
  return (b * b - a * a) / (s * (s + 2.0));
}

double jacobiB(double a, double b, int n) {
  if (n == 0) return 1.0;
  if (n == 1) return 4.0 * (a + 1.0) * (b + 1.0) / ((a + b + 2.0) * (a + b + 2.0) * (a + b + 3.0));
  const double s = 2.0 * n + a + b;
  return 4.0 * n * (n + a) * (n + b) * (n + a + b) / (s * s * (s + 1.0) * (s - 1.0));
}

}  // namespace

OrthonormalFamily::OrthonormalFamily(const GermSpec& germ) : germ_(germ) {
  const bool needs_alpha = germ.family == GermFamily::kBeta || germ.family == GermFamily::kGamma;
  const bool needs_beta = germ.family == GermFamily::kBeta;
  if ((needs_alpha && !(germ.alpha > 0.0 && std::isfinite(germ.alpha))) ||
      (needs_beta && !(germ.beta > 0.0 && std::isfinite(germ.beta)))) {
    throw std::invalid_argument("invalid germ shape for " + describe(germ) +
                                ": shapes must be positive and finite");
  }
}

double OrthonormalFamily::recurrenceA(int n) const {
  switch (germ_.family) {
    case GermFamily::kBeta:
      return jacobiA(germ_.beta - 1.0, germ_.alpha - 1.0, n);
    case GermFamily::kUniform:
    case GermFamily::kGaussian:
      return 0.0;
    case GermFamily::kGamma:
      return 2.0 * n + germ_.alpha;
  }
  return 0.0;
}

double OrthonormalFamily::recurrenceB(int n) const {
  if (n == 0) return 1.0;
  switch (germ_.family) {
    case GermFamily::kBeta:
      return jacobiB(germ_.beta - 1.0, germ_.alpha - 1.0, n);
    case GermFamily::kUniform:
      return n * n / (4.0 * n * n - 1.0);
    case GermFamily::kGaussian:
      return n;
    case GermFamily::kGamma:
      return n * (n + germ_.alpha - 1.0);
  }
  return 0.0;
}

void OrthonormalFamily::evaluate(double x, int degree, double* out) const {
  if (degree < 0) return;
  out[0] = 1.0;
  if (degree == 0) return;
  double sqrt_b = std::sqrt(recurrenceB(1));
  out[1] = (x - recurrenceA(0)) / sqrt_b;
  for (int n = 1; n < degree; ++n) {
    const double sqrt_b_next = std::sqrt(recurrenceB(n + 1));
    out[n + 1] = ((x - recurrenceA(n)) * out[n] - sqrt_b * out[n - 1]) / sqrt_b_next;
    sqrt_b = sqrt_b_next;
  }
}

Eigen::VectorXd OrthonormalFamily::evaluate(double x, int degree) const {
  Eigen::VectorXd out(degree + 1);
  evaluate(x, degree, out.data());
  return out;
}

QuadratureRule OrthonormalFamily::gaussRule(int n) const {
  if (n < 1) throw std::invalid_argument("gaussRule: need at least one node");
  Eigen::MatrixXd jacobi = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i) {
    jacobi(i, i) = recurrenceA(i);
    if (i + 1 < n) jacobi(i, i + 1) = jacobi(i + 1, i) = std::sqrt(recurrenceB(i + 1));
  }
  // Eigen returns eigenvalues in ascending order, so the nodes come sorted.
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(jacobi);
  QuadratureRule rule;
  rule.nodes = solver.eigenvalues();
  rule.weights = solver.eigenvectors().row(0).transpose().array().square();  // times b_0 = 1
  return rule;
}

double OrthonormalFamily::pdf(double x) const {
  switch (germ_.family) {
    case GermFamily::kBeta: {
      if (x < -1.0 || x > 1.0) return 0.0;
      const double a = germ_.alpha;
      const double b = germ_.beta;
      // Density of s = (x + 1)/2 ~ Beta(a, b) on [0, 1], times ds/dx = 1/2.
      const double s = 0.5 * (x + 1.0);
      const double log_norm = std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b);
      return 0.5 * std::exp(log_norm + (a - 1.0) * std::log(s) + (b - 1.0) * std::log1p(-s));
    }
    case GermFamily::kUniform:
      return (x < -1.0 || x > 1.0) ? 0.0 : 0.5;
    case GermFamily::kGaussian:
      return std::exp(-0.5 * x * x) / std::sqrt(2.0 * M_PI);
    case GermFamily::kGamma: {
      if (x < 0.0) return 0.0;
      const double k = germ_.alpha;
      if (x == 0.0) return k < 1.0 ? kInf : (k == 1.0 ? 1.0 : 0.0);
      return std::exp((k - 1.0) * std::log(x) - x - std::lgamma(k));
    }
  }
  return 0.0;
}

double OrthonormalFamily::cdf(double x) const {
  switch (germ_.family) {
    case GermFamily::kBeta:
      if (isBeta22(germ_)) return beta22Cdf(x);
      return regularizedIncompleteBeta(germ_.alpha, germ_.beta,
                                       std::min(1.0, std::max(0.0, 0.5 * (x + 1.0))));
    case GermFamily::kUniform:
      return std::min(1.0, std::max(0.0, 0.5 * (x + 1.0)));
    case GermFamily::kGaussian:
      return normalCdf(x);
    case GermFamily::kGamma:
      return regularizedLowerIncompleteGamma(germ_.alpha, x);
  }
  return 0.0;
}

double OrthonormalFamily::inverseCdf(double u) const {
  if (!(u > 0.0 && u < 1.0)) {
    throw std::invalid_argument("inverseCdf of " + describe(germ_) + ": u = " + std::to_string(u) +
                                " is outside (0, 1)");
  }
  switch (germ_.family) {
    case GermFamily::kBeta: {
      if (isBeta22(germ_)) return beta22InverseCdf(u);
      const double a = germ_.alpha;
      const double b = germ_.beta;
      // Solve in s = (x + 1)/2 so the bracket is [0, 1]; start at the mean.
      const auto cdf_s = [a, b](double s) { return regularizedIncompleteBeta(a, b, s); };
      const auto pdf_s = [this](double s) { return 2.0 * pdf(2.0 * s - 1.0); };
      return 2.0 * solveMonotoneCdf(cdf_s, pdf_s, u, 0.0, 1.0, a / (a + b)) - 1.0;
    }
    case GermFamily::kUniform:
      return 2.0 * u - 1.0;
    case GermFamily::kGaussian:
      return normalInverseCdf(u);
    case GermFamily::kGamma: {
      const double k = germ_.alpha;
      const auto cdf = [k](double x) { return regularizedLowerIncompleteGamma(k, x); };
      const auto pdf = [this](double x) { return this->pdf(x); };
      double hi = k + 10.0 * std::sqrt(k) + 10.0;
      while (cdf(hi) < u) hi *= 2.0;
      // Wilson-Hilferty start: (x/k)^(1/3) is nearly normal.
      const double z = normalInverseCdf(u);
      const double c = 1.0 / (9.0 * k);
      const double start = k * std::pow(std::max(1.0 - c + z * std::sqrt(c), 1e-3), 3.0);
      return solveMonotoneCdf(cdf, pdf, u, 0.0, hi, start);
    }
  }
  return 0.0;
}

double OrthonormalFamily::lower() const {
  switch (germ_.family) {
    case GermFamily::kBeta:
    case GermFamily::kUniform:
      return -1.0;
    case GermFamily::kGaussian:
      return -kInf;
    case GermFamily::kGamma:
      return 0.0;
  }
  return -kInf;
}

double OrthonormalFamily::upper() const {
  return (germ_.family == GermFamily::kBeta || germ_.family == GermFamily::kUniform) ? 1.0 : kInf;
}

double beta22InverseCdf(double u) {
  if (!(u > 0.0 && u < 1.0)) {
    throw std::invalid_argument("beta22InverseCdf: u = " + std::to_string(u) +
                                " is outside (0, 1)");
  }
  return 2.0 * std::cos((std::acos(1.0 - 2.0 * u) - 2.0 * M_PI) / 3.0);
}

double beta22Cdf(double x) {
  if (x <= -1.0) return 0.0;
  if (x >= 1.0) return 1.0;
  const double s = 0.5 * (x + 1.0);
  return s * s * (3.0 - 2.0 * s);
}

}  // namespace pc_ekf
