#include "pc_ekf/pc/special_functions.h"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace pc_ekf {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();
constexpr double kTiny = 1e-300;
constexpr int kMaxIterations = 10000;

// Modified Lentz evaluation of the incomplete-beta continued fraction
// (Numerical Recipes, betacf), converging fast for x < (a + 1) / (a + b + 2).
double betaContinuedFraction(double a, double b, double x) {
  const double qab = a + b;
  const double qap = a + 1.0;
  const double qam = a - 1.0;
  double c = 1.0;
  double d = 1.0 - qab * x / qap;
  if (std::fabs(d) < kTiny) d = kTiny;
  d = 1.0 / d;
  double h = d;
  for (int m = 1; m <= kMaxIterations; ++m) {
    const int m2 = 2 * m;
    double aa = m * (b - m) * x / ((qam + m2) * (a + m2));
    d = 1.0 + aa * d;
    if (std::fabs(d) < kTiny) d = kTiny;
    c = 1.0 + aa / c;
    if (std::fabs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    h *= d * c;
    aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
    d = 1.0 + aa * d;
    if (std::fabs(d) < kTiny) d = kTiny;
    c = 1.0 + aa / c;
    if (std::fabs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double del = d * c;
    h *= del;
    if (std::fabs(del - 1.0) <= kEps) return h;
  }
  throw std::runtime_error("regularizedIncompleteBeta: continued fraction did not converge");
}

// P(a, x) by its power series; converges fast for x < a + 1.
double gammaSeries(double a, double x) {
  double ap = a;
  double del = 1.0 / a;
  double sum = del;
  for (int n = 0; n < kMaxIterations; ++n) {
    ap += 1.0;
    del *= x / ap;
    sum += del;
    if (std::fabs(del) < std::fabs(sum) * kEps) {
      return sum * std::exp(-x + a * std::log(x) - std::lgamma(a));
    }
  }
  throw std::runtime_error("regularizedLowerIncompleteGamma: series did not converge");
}

// Q(a, x) = 1 - P(a, x) by its continued fraction (modified Lentz); for x >= a + 1.
double gammaContinuedFraction(double a, double x) {
  double b = x + 1.0 - a;
  double c = 1.0 / kTiny;
  double d = 1.0 / b;
  double h = d;
  for (int i = 1; i <= kMaxIterations; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::fabs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::fabs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double del = d * c;
    h *= del;
    if (std::fabs(del - 1.0) <= kEps) {
      return std::exp(-x + a * std::log(x) - std::lgamma(a)) * h;
    }
  }
  throw std::runtime_error("regularizedLowerIncompleteGamma: continued fraction did not converge");
}

// Acklam's rational approximation of the normal quantile (relative error 1.15e-9).
double acklamInverseCdf(double u) {
  static const double a[] = {-3.969683028665376e+01, 2.209460984245205e+02,  -2.759285104469687e+02,
                             1.383577518672690e+02,  -3.066479806614716e+01, 2.506628277459239e+00};
  static const double b[] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                             6.680131188771972e+01, -1.328068155288572e+01};
  static const double c[] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                             -2.549732539343734e+00, 4.374664141464968e+00,  2.938163982698783e+00};
  static const double d[] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00,
                             3.754408661907416e+00};
  constexpr double kLow = 0.02425;
  if (u < kLow) {
    const double q = std::sqrt(-2.0 * std::log(u));
    return (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
           ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
  }
  const double q = u - 0.5;
  const double r = q * q;
  return (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
         (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1.0);
}

}  // namespace

double regularizedIncompleteBeta(double a, double b, double x) {
  if (!(a > 0.0) || !(b > 0.0)) {
    throw std::invalid_argument("regularizedIncompleteBeta: shapes must be positive");
  }
  if (std::isnan(x)) return x;
  if (x <= 0.0) return 0.0;
  if (x >= 1.0) return 1.0;
  const double front = std::exp(std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) +
                                a * std::log(x) + b * std::log1p(-x));
  // The continued fraction converges fast only on one side of the mean; use the
  // symmetry I_x(a, b) = 1 - I_{1-x}(b, a) on the other.
  if (x < (a + 1.0) / (a + b + 2.0)) return front * betaContinuedFraction(a, b, x) / a;
  return 1.0 - front * betaContinuedFraction(b, a, 1.0 - x) / b;
}

double regularizedLowerIncompleteGamma(double a, double x) {
  if (!(a > 0.0)) {
    throw std::invalid_argument("regularizedLowerIncompleteGamma: shape must be positive");
  }
  if (std::isnan(x)) return x;
  if (x <= 0.0) return 0.0;
  if (std::isinf(x)) return 1.0;
  if (x < a + 1.0) return gammaSeries(a, x);
  return 1.0 - gammaContinuedFraction(a, x);
}

double normalCdf(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

double normalInverseCdf(double u) {
  if (!(u > 0.0 && u < 1.0)) {
    throw std::invalid_argument("normalInverseCdf: u must lie in (0, 1)");
  }
  // Work in the lower tail, where u carries full relative precision (1 - u is
  // exact for u >= 1/2), and reflect.
  if (u > 0.5) return -normalInverseCdf(1.0 - u);
  if (u == 0.5) return 0.0;
  double x = acklamInverseCdf(u);
  // Halley steps on cdf(x) - u; erfc keeps the residual relatively accurate in the tail.
  for (int i = 0; i < 2; ++i) {
    const double e = normalCdf(x) - u;
    const double t = e * std::sqrt(2.0 * M_PI) * std::exp(0.5 * x * x);
    x -= t / (1.0 + 0.5 * x * t);
  }
  return x;
}

double solveMonotoneCdf(const std::function<double(double)>& cdf,
                        const std::function<double(double)>& pdf, double u, double lo, double hi,
                        double x0) {
  double x = (x0 > lo && x0 < hi) ? x0 : 0.5 * (lo + hi);
  double previous_step = hi - lo;
  for (int i = 0; i < 400; ++i) {
    const double f = cdf(x) - u;
    if (f == 0.0) return x;
    if (f < 0.0) {
      lo = x;
    } else {
      hi = x;
    }
    const double slope = pdf(x);
    double next = (slope > 0.0 && std::isfinite(slope)) ? x - f / slope : lo - 1.0;
    // Bisect when Newton leaves the bracket or stalls (fewer than halving steps).
    if (!(next > lo && next < hi) || std::fabs(next - x) > 0.5 * previous_step) {
      next = 0.5 * (lo + hi);
    }
    previous_step = std::fabs(next - x);
    x = next;
    if (previous_step <= 4.0 * kEps * std::fabs(x) || hi - lo <= 4.0 * kEps * std::fabs(x) ||
        previous_step == 0.0) {
      return x;
    }
  }
  return x;
}

}  // namespace pc_ekf
