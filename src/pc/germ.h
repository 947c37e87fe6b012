// Random germs of the polynomial chaos expansion and their Wiener-Askey
// polynomial families (docs/method.md §3.1).
#pragma once

#include <string>

namespace pc_ekf {

enum class GermFamily {
  kBeta,      // Beta(alpha, beta) on [-1, 1]  -> Jacobi P^(beta-1, alpha-1)
  kUniform,   // uniform on [-1, 1]            -> Legendre
  kGaussian,  // standard normal               -> probabilists' Hermite
  kGamma,     // Gamma(shape, 1) on [0, inf)   -> generalised Laguerre L^(shape-1)
};

// Shape convention: for kBeta the density on [-1, 1] is proportional to
// (1 + x)^(alpha - 1) (1 - x)^(beta - 1), so Beta(2, 2) has w(x) = 3/4 (1 - x^2)
// and its orthogonal polynomials are Jacobi P^(1,1). For kGamma, `alpha` is the
// shape k (density x^(k-1) e^(-x) / Gamma(k)); `beta` is unused. Other
// families ignore both.
struct GermSpec {
  GermFamily family = GermFamily::kBeta;
  double alpha = 2.0;
  double beta = 2.0;
};

// "beta", "uniform", "gaussian", "gamma".
std::string toString(GermFamily family);
// Throws std::invalid_argument naming the accepted values.
GermFamily germFamilyFromString(const std::string& name);
// Human-readable, e.g. "beta(2,2)".
std::string describe(const GermSpec& germ);

// Mean and standard deviation of the germ under its own measure (e.g. 0 and
// 1/sqrt(5) for Beta(2, 2) on [-1, 1]).
double germMean(const GermSpec& germ);
double germStddev(const GermSpec& germ);

}  // namespace pc_ekf
