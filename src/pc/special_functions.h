// Scalar distribution functions behind the germs' CDFs and inverse CDFs (docs/method.md §3.1).
#pragma once

#include <functional>

namespace pc_ekf {

// Regularized incomplete beta I_x(a, b), x in [0, 1], a, b > 0 (continued fraction).
double regularizedIncompleteBeta(double a, double b, double x);
// Regularized lower incomplete gamma P(a, x), x >= 0, a > 0 (series / continued fraction).
double regularizedLowerIncompleteGamma(double a, double x);

// Standard normal CDF and its inverse (Acklam start + Halley steps, ~1e-15).
double normalCdf(double x);
double normalInverseCdf(double u);

// Solves cdf(x) = u for a monotone cdf on the bracket [lo, hi] (finite, with
// cdf(lo) <= u <= cdf(hi)) by Newton steps from x0, falling back to bisection
// whenever a step leaves the bracket or does not shrink the residual enough.
double solveMonotoneCdf(const std::function<double(double)>& cdf,
                        const std::function<double(double)>& pdf, double u, double lo, double hi,
                        double x0);

}  // namespace pc_ekf
