// Univariate orthonormal families, Gauss rules and germ distributions (docs/method.md §3.1, §3.2).
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "pc_ekf/pc/orthonormal_family.h"
#include "pc_ekf/pc/special_functions.h"

namespace pc_ekf {
namespace {

GermSpec beta(double a, double b) { return {GermFamily::kBeta, a, b}; }
GermSpec uniform() { return {GermFamily::kUniform, 0.0, 0.0}; }
GermSpec gaussian() { return {GermFamily::kGaussian, 0.0, 0.0}; }
GermSpec gamma(double k) { return {GermFamily::kGamma, k, 0.0}; }

std::vector<GermSpec> allFamilies() {
  return {beta(2, 2), beta(2, 5), beta(0.5, 0.5), uniform(), gaussian(), gamma(2), gamma(0.5)};
}

double binomial(double n, double k) {
  return std::exp(std::lgamma(n + 1) - std::lgamma(k + 1) - std::lgamma(n - k + 1));
}

// Raw moment E[t^m] from closed forms independent of the recurrence, with
// t = (x + 1)/2 ~ Beta(alpha, beta) on [0, 1] for the Beta family (moments of x
// itself would suffer cancellation), t = x otherwise.
double rawMoment(const GermSpec& g, int m) {
  double v = 1.0;
  switch (g.family) {
    case GermFamily::kBeta:
      for (int i = 0; i < m; ++i) v *= (g.alpha + i) / (g.alpha + g.beta + i);
      return v;
    case GermFamily::kUniform:
      return m % 2 ? 0.0 : 1.0 / (m + 1);
    case GermFamily::kGaussian:
      if (m % 2) return 0.0;
      for (int i = m - 1; i > 0; i -= 2) v *= i;  // (m-1)!!
      return v;
    case GermFamily::kGamma:
      for (int i = 0; i < m; ++i) v *= g.alpha + i;
      return v;
  }
  return 0.0;
}

TEST(OrthonormalFamily, GaussRuleReproducesIndependentMoments) {
  // Guards the recurrence coefficients: the orthonormality check below uses the
  // family's own Gauss rule, so the rule itself must match the true measure.
  for (const GermSpec& g : allFamilies()) {
    const QuadratureRule rule = OrthonormalFamily(g).gaussRule(10);
    EXPECT_NEAR(rule.weights.sum(), 1.0, 1e-14) << describe(g);
    Eigen::ArrayXd t = rule.nodes.array();
    if (g.family == GermFamily::kBeta) t = 0.5 * (t + 1.0);
    for (int m = 1; m <= 19; ++m) {
      const Eigen::ArrayXd tm = t.pow(m);
      const double quad = (rule.weights.array() * tm).sum();
      const double scale = (rule.weights.array() * tm.abs()).sum();  // rounding scale
      EXPECT_NEAR(quad, rawMoment(g, m), 1e-12 * scale) << describe(g) << " m=" << m;
    }
  }
}

TEST(OrthonormalFamily, OrthonormalUpToDegree8ByGaussQuadrature) {
  for (const GermSpec& g : allFamilies()) {
    const OrthonormalFamily family(g);
    const QuadratureRule rule = family.gaussRule(12);  // exact to degree 23 >= 16
    Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(9, 9);
    for (int q = 0; q < rule.nodes.size(); ++q) {
      const Eigen::VectorXd psi = family.evaluate(rule.nodes(q), 8);
      gram += rule.weights(q) * psi * psi.transpose();
    }
    const double err = (gram - Eigen::MatrixXd::Identity(9, 9)).cwiseAbs().maxCoeff();
    EXPECT_LT(err, 1e-12) << describe(g);
  }
}

TEST(OrthonormalFamily, Beta25OrthonormalUnderIndependentLegendreQuadrature) {
  // Beta(2,5) density is a polynomial of degree 5, so a Legendre rule (a different
  // family) integrates psi_i psi_j pdf exactly: E[f] = 2 E_uniform[f pdf].
  const OrthonormalFamily family(beta(2, 5));
  const QuadratureRule rule = OrthonormalFamily(uniform()).gaussRule(14);
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(9, 9);
  for (int q = 0; q < rule.nodes.size(); ++q) {
    const double x = rule.nodes(q);
    const Eigen::VectorXd psi = family.evaluate(x, 8);
    gram += 2.0 * rule.weights(q) * family.pdf(x) * psi * psi.transpose();
  }
  EXPECT_LT((gram - Eigen::MatrixXd::Identity(9, 9)).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(OrthonormalFamily, GaussNodesSortedAndExactForKnownRules) {
  // 2-point Hermite nodes are +-1; 3-point Legendre nodes 0, +-sqrt(3/5), weights 5/18, 4/9.
  const QuadratureRule h = OrthonormalFamily(gaussian()).gaussRule(2);
  EXPECT_NEAR(h.nodes(0), -1.0, 1e-15);
  EXPECT_NEAR(h.nodes(1), 1.0, 1e-15);
  const QuadratureRule l = OrthonormalFamily(uniform()).gaussRule(3);
  EXPECT_NEAR(l.nodes(0), -std::sqrt(0.6), 1e-15);
  EXPECT_NEAR(l.nodes(1), 0.0, 1e-15);
  EXPECT_NEAR(l.nodes(2), std::sqrt(0.6), 1e-15);
  EXPECT_NEAR(l.weights(0), 5.0 / 18.0, 1e-15);
  EXPECT_NEAR(l.weights(1), 4.0 / 9.0, 1e-15);
  const QuadratureRule g = OrthonormalFamily(gamma(2)).gaussRule(15);
  for (int i = 1; i < 15; ++i) EXPECT_LT(g.nodes(i - 1), g.nodes(i));
}

TEST(OrthonormalFamily, Jacobi11MatchesExplicitSumFormula) {
  // P_n^(1,1)(x) = sum_s C(n+1, n-s) C(n+1, s) ((x-1)/2)^s ((x+1)/2)^(n-s), and
  // E[P_n^2] = [2^3 Gamma(n+2)^2 / ((2n+3) n! Gamma(n+3))] / (4/3) under Beta(2,2).
  const OrthonormalFamily family(beta(2, 2));
  for (double x : {-0.97, -0.5, -0.1, 0.0, 0.33, 0.8, 1.0}) {
    const Eigen::VectorXd psi = family.evaluate(x, 8);
    for (int n = 0; n <= 8; ++n) {
      double p = 0.0;
      for (int s = 0; s <= n; ++s) {
        p += binomial(n + 1, n - s) * binomial(n + 1, s) * std::pow((x - 1) / 2, s) *
             std::pow((x + 1) / 2, n - s);
      }
      const double norm2 =
          8.0 * std::exp(2 * std::lgamma(n + 2.0) - std::lgamma(n + 1.0) - std::lgamma(n + 3.0)) /
          (2 * n + 3) / (4.0 / 3.0);
      EXPECT_NEAR(psi(n), p / std::sqrt(norm2), 1e-12) << "n=" << n << " x=" << x;
    }
  }
  // The docs/method.md §3.2 example: psi_1 = sqrt(5) xi.
  EXPECT_NEAR(family.evaluate(0.3, 1)(1), std::sqrt(5.0) * 0.3, 1e-15);
}

TEST(OrthonormalFamily, HermiteMatchesHeClosedForms) {
  const OrthonormalFamily family(gaussian());
  for (double x : {-2.5, -1.0, 0.0, 0.7, 3.0}) {
    const Eigen::VectorXd psi = family.evaluate(x, 5);
    const double he[] = {1.0,
                         x,
                         x * x - 1,
                         x * x * x - 3 * x,
                         std::pow(x, 4) - 6 * x * x + 3,
                         std::pow(x, 5) - 10 * std::pow(x, 3) + 15 * x};
    double factorial = 1.0;
    for (int n = 0; n <= 5; ++n) {
      if (n > 0) factorial *= n;
      EXPECT_NEAR(psi(n), he[n] / std::sqrt(factorial), 1e-12) << "n=" << n << " x=" << x;
    }
  }
}

TEST(OrthonormalFamily, LegendreMatchesKnownPolynomials) {
  const OrthonormalFamily family(uniform());
  for (double x : {-1.0, -0.6, 0.2, 0.9}) {
    const Eigen::VectorXd psi = family.evaluate(x, 4);
    const double p[] = {1.0, x, (3 * x * x - 1) / 2, (5 * x * x * x - 3 * x) / 2,
                        (35 * std::pow(x, 4) - 30 * x * x + 3) / 8};
    for (int n = 0; n <= 4; ++n) {
      EXPECT_NEAR(psi(n), std::sqrt(2.0 * n + 1) * p[n], 1e-13) << "n=" << n << " x=" << x;
    }
  }
}

TEST(OrthonormalFamily, LaguerreMatchesExplicitSumFormula) {
  // Gamma(k): psi_n = (-1)^n L_n^(k-1) / sqrt(Gamma(n+k) / (n! Gamma(k))),
  // L_n^(a)(x) = sum_i (-1)^i C(n+a, n-i) x^i / i!.
  for (double k : {2.0, 0.5}) {
    const OrthonormalFamily family(gamma(k));
    for (double x : {0.0, 0.4, 2.0, 7.5}) {
      const Eigen::VectorXd psi = family.evaluate(x, 6);
      for (int n = 0; n <= 6; ++n) {
        double l = 0.0;
        for (int i = 0; i <= n; ++i) {
          l += std::pow(-1.0, i) * binomial(n + k - 1, n - i) * std::pow(x, i) /
               std::exp(std::lgamma(i + 1.0));
        }
        const double norm2 = std::exp(std::lgamma(n + k) - std::lgamma(n + 1.0) - std::lgamma(k));
        EXPECT_NEAR(psi(n), std::pow(-1.0, n) * l / std::sqrt(norm2),
                    1e-12 * std::max(1.0, std::fabs(psi(n))))
            << "k=" << k << " n=" << n << " x=" << x;
      }
    }
  }
}

TEST(OrthonormalFamily, RecurrenceCoefficientsOfTheHeader) {
  const OrthonormalFamily h(gaussian());
  const OrthonormalFamily l(gamma(2));
  const OrthonormalFamily j(beta(2, 2));
  for (int n = 1; n <= 6; ++n) {
    EXPECT_DOUBLE_EQ(h.recurrenceA(n), 0.0);
    EXPECT_DOUBLE_EQ(h.recurrenceB(n), n);
    EXPECT_DOUBLE_EQ(l.recurrenceA(n), 2.0 * n + 2.0);
    EXPECT_DOUBLE_EQ(l.recurrenceB(n), n * (n + 1.0));
    // Gegenbauer lambda = 3/2: b_n = n (n + 2) / ((2n + 1)(2n + 3)).
    EXPECT_NEAR(j.recurrenceB(n), n * (n + 2.0) / ((2 * n + 1.0) * (2 * n + 3.0)), 1e-15);
  }
  EXPECT_DOUBLE_EQ(j.recurrenceB(0), 1.0);
  EXPECT_NEAR(j.recurrenceB(1), 0.2, 1e-15);  // E[xi^2] = 1/5 (docs/method.md §3.2)
  // Beta(2,5) mean on [-1,1]: 2 * 2/7 - 1 = -3/7.
  EXPECT_NEAR(OrthonormalFamily(beta(2, 5)).recurrenceA(0), -3.0 / 7.0, 1e-15);
  // a + b = -1 (Beta(0.5, 0.5): Chebyshev first kind): b_1 = 1/2, b_n = 1/4.
  const OrthonormalFamily c(beta(0.5, 0.5));
  EXPECT_NEAR(c.recurrenceB(1), 0.5, 1e-15);
  EXPECT_NEAR(c.recurrenceB(2), 0.25, 1e-15);
  EXPECT_NEAR(c.recurrenceA(0), 0.0, 1e-15);
  // a + b = 0 with a != b (Beta(1.5, 0.5)): a_0 = (b - a)/(a + b + 2) = (0.5 + 0.5)/2.
  EXPECT_NEAR(OrthonormalFamily(beta(1.5, 0.5)).recurrenceA(0), 0.5, 1e-15);
}

TEST(OrthonormalFamily, RejectsInvalidShapes) {
  EXPECT_THROW(OrthonormalFamily(beta(0.0, 2.0)), std::invalid_argument);
  EXPECT_THROW(OrthonormalFamily(beta(2.0, -1.0)), std::invalid_argument);
  EXPECT_THROW(OrthonormalFamily(gamma(0.0)), std::invalid_argument);
  EXPECT_NO_THROW(OrthonormalFamily{gaussian()});
}

TEST(GermDistribution, Beta22ClosedForms) {
  // s = 0.2 -> 3 s^2 - 2 s^3 = 0.104, i.e. xi = -0.6.
  EXPECT_NEAR(beta22Cdf(-0.6), 0.104, 1e-15);
  EXPECT_NEAR(beta22InverseCdf(0.104), -0.6, 1e-14);
  EXPECT_NEAR(beta22InverseCdf(0.5), 0.0, 1e-15);
  EXPECT_NEAR(beta22InverseCdf(0.896), 0.6, 1e-14);
  EXPECT_EQ(beta22Cdf(-1.5), 0.0);
  EXPECT_EQ(beta22Cdf(1.5), 1.0);
  EXPECT_NEAR(OrthonormalFamily(beta(2, 2)).pdf(0.5), 0.75 * 0.75, 1e-15);
}

TEST(GermDistribution, Beta22InverseCdfRoundTripsTo1e14) {
  const OrthonormalFamily family(beta(2, 2));
  std::vector<double> grid = {1e-12, 1e-8, 1e-4, 1 - 1e-4, 1 - 1e-8};
  for (int i = 1; i < 1000; ++i) grid.push_back(i / 1000.0);
  for (double u : grid) {
    const double x = beta22InverseCdf(u);
    EXPECT_NEAR(beta22Cdf(x), u, 1e-14) << "u=" << u;
    EXPECT_EQ(family.inverseCdf(u), x);
    EXPECT_EQ(family.cdf(x), beta22Cdf(x));
  }
}

TEST(GermDistribution, IncompleteFunctionsMatchClosedForms) {
  for (double s : {0.01, 0.2, 0.5, 0.77, 0.99}) {
    // Integer shapes: I_s(a, b) = sum_{j=a}^{a+b-1} C(a+b-1, j) s^j (1-s)^(a+b-1-j).
    double i25 = 0.0;
    for (int j = 2; j <= 6; ++j) i25 += binomial(6, j) * std::pow(s, j) * std::pow(1 - s, 6 - j);
    EXPECT_NEAR(regularizedIncompleteBeta(2, 5, s), i25, 1e-14) << s;
    EXPECT_NEAR(regularizedIncompleteBeta(1, 3.5, s), 1 - std::pow(1 - s, 3.5), 1e-14) << s;
    EXPECT_NEAR(regularizedIncompleteBeta(0.5, 0.5, s), 2 / M_PI * std::asin(std::sqrt(s)), 1e-14);
  }
  for (double x : {0.01, 0.5, 2.0, 3.5, 10.0, 40.0}) {
    EXPECT_NEAR(regularizedLowerIncompleteGamma(1, x), -std::expm1(-x), 1e-14) << x;
    EXPECT_NEAR(regularizedLowerIncompleteGamma(2, x), 1 - (1 + x) * std::exp(-x), 1e-14) << x;
    EXPECT_NEAR(regularizedLowerIncompleteGamma(0.5, x), std::erf(std::sqrt(x)), 1e-14) << x;
  }
}

TEST(GermDistribution, NormalQuantileReferenceValues) {
  EXPECT_NEAR(normalInverseCdf(0.975), 1.959963984540054, 1e-14);
  EXPECT_NEAR(normalInverseCdf(0.5), 0.0, 1e-16);
  EXPECT_NEAR(normalInverseCdf(1e-10), -6.361340902404056, 1e-13);
  EXPECT_NEAR(normalInverseCdf(0.8413447460685429), 1.0, 1e-14);
  EXPECT_NEAR(normalCdf(-1.0), 0.15865525393145705, 1e-16);
}

TEST(GermDistribution, GeneralInverseCdfsRoundTripTo1e12) {
  std::vector<double> grid = {1e-10, 1e-6, 1e-3, 0.999, 1 - 1e-6};
  for (int i = 1; i < 200; ++i) grid.push_back(i / 200.0);
  for (const GermSpec& g : {beta(2, 5), beta(0.5, 0.5), beta(3, 1.5), uniform(), gaussian(),
                            gamma(2), gamma(0.5), gamma(10)}) {
    const OrthonormalFamily family(g);
    for (double u : grid) {
      // Beta(0.5, 0.5) has u ~ sqrt(1 + x) near x = -1, where doubles are spaced
      // 1.1e-16: u below ~1e-3 is not resolvable to 1e-12 by any x in [-1, 1].
      if (g.alpha < 1.0 && g.family == GermFamily::kBeta && std::fabs(u - 0.5) > 0.499) continue;
      const double x = family.inverseCdf(u);
      EXPECT_GE(x, family.lower()) << describe(g);
      EXPECT_LE(x, family.upper()) << describe(g);
      EXPECT_NEAR(family.cdf(x), u, 1e-12) << describe(g) << " u=" << u;
    }
  }
}

TEST(GermDistribution, CdfIsTheIntegralOfThePdf) {
  // Independent of the incomplete beta/gamma: Gauss-Legendre on [lower, x].
  const QuadratureRule rule = OrthonormalFamily(uniform()).gaussRule(40);
  for (const GermSpec& g : {beta(2, 5), beta(3, 1.5), gamma(2), gaussian()}) {
    const OrthonormalFamily family(g);
    // Inside the support, away from the Beta endpoint singularities.
    for (double x : {-0.5, 0.1, 0.6, 0.95}) {
      const double a = g.family == GermFamily::kGaussian ? -12.0 : std::max(family.lower(), -1.0);
      const double b = x;
      if (b <= a) continue;
      double integral = 0.0;
      for (int q = 0; q < rule.nodes.size(); ++q) {
        integral += rule.weights(q) * (b - a) * family.pdf(a + (b - a) * 0.5 * (rule.nodes(q) + 1));
      }
      EXPECT_NEAR(family.cdf(x), integral, 1e-12) << describe(g) << " x=" << x;
    }
  }
}

TEST(GermDistribution, InverseCdfRejectsOutOfRange) {
  for (const GermSpec& g : allFamilies()) {
    const OrthonormalFamily family(g);
    EXPECT_THROW(family.inverseCdf(0.0), std::invalid_argument) << describe(g);
    EXPECT_THROW(family.inverseCdf(1.0), std::invalid_argument) << describe(g);
    EXPECT_THROW(family.inverseCdf(-0.2), std::invalid_argument) << describe(g);
    EXPECT_THROW(family.inverseCdf(std::nan("")), std::invalid_argument) << describe(g);
  }
  EXPECT_THROW(beta22InverseCdf(1.0), std::invalid_argument);
}

TEST(Germ, NamesRoundTrip) {
  for (GermFamily f :
       {GermFamily::kBeta, GermFamily::kUniform, GermFamily::kGaussian, GermFamily::kGamma}) {
    EXPECT_EQ(germFamilyFromString(toString(f)), f);
  }
  EXPECT_THROW(germFamilyFromString("poisson"), std::invalid_argument);
  EXPECT_EQ(describe(beta(2, 2)), "beta(2,2)");
  EXPECT_EQ(describe(beta(2, 5)), "beta(2,5)");
  EXPECT_EQ(describe(gamma(1.5)), "gamma(1.5)");
  EXPECT_EQ(describe(gaussian()), "gaussian");
}

// germMean / germStddev (closed forms) against the family's own Gauss rule.
TEST(GermMoments, ClosedFormsEqualTheGaussRuleMoments) {
  for (const GermSpec& g :
       {GermSpec{GermFamily::kBeta, 2.0, 2.0}, GermSpec{GermFamily::kBeta, 1.5, 4.0},
        GermSpec{GermFamily::kUniform, 0, 0}, GermSpec{GermFamily::kGaussian, 0, 0},
        GermSpec{GermFamily::kGamma, 2.5, 0}}) {
    const QuadratureRule rule = OrthonormalFamily(g).gaussRule(6);
    const double mean = rule.weights.dot(rule.nodes);
    const double var = rule.weights.dot((rule.nodes.array() - mean).square().matrix());
    EXPECT_NEAR(germMean(g), mean, 1e-12) << describe(g);
    EXPECT_NEAR(germStddev(g), std::sqrt(var), 1e-12) << describe(g);
  }
  EXPECT_NEAR(germStddev(GermSpec{}), 1.0 / std::sqrt(5.0), 1e-15);  // Beta(2, 2)
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
