// Inline tanh and cos for the damper law and the roll lever (docs/method.md §1.2, §1.4): glibc's
// calls were 2/3 of the RK4 cost. Accuracy: a few ulp. And sin for the ISO 8608
// road's harmonics (glibc's sin was 45 % of a turns.yaml run).
//
// Everything here is straight-line arithmetic (no branch, no library call on
// the common path), so a loop over the collocation points that calls these
// vectorises; and because it is plain IEEE arithmetic (no reassociation), a
// vectorised loop gives bit for bit the values of its own scalar remainder
// loop. (A function compiled with FMA, e.g. a target_clones "x86-64-v3" clone,
// contracts a * b + c and so may differ from a build without FMA in the last
// bit; each point's value never depends on the batch it is in.)
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>

namespace pc_ekf {

namespace smooth_detail {

inline std::uint64_t bitsOf(double x) {
  std::uint64_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}
inline double fromBits(std::uint64_t b) {
  double x;
  std::memcpy(&x, &b, sizeof x);
  return x;
}
// condition ? a : b as a bit mask: both operands are evaluated, so the compiler
// cannot sink either into a branch (a branch would stop vectorisation).
inline double select(bool condition, double a, double b) {
  const std::uint64_t mask = std::uint64_t{0} - static_cast<std::uint64_t>(condition);
  return fromBits((bitsOf(a) & mask) | (bitsOf(b) & ~mask));
}

}  // namespace smooth_detail

// tanh: Cephes' rational form for |x| < 0.625 (keeps relative accuracy and
// tanh(0) = 0); elsewhere (e^2a - 1) / (e^2a + 1), e^2a = 2^n e^r with
// e^r = (Q + P) / (Q - P) (Cephes' exp Pade form, r = 2a - n ln 2), so that
// tanh = (2^n (Q + P) - (Q - P)) / (2^n (Q + P) + (Q - P)): no cancellation
// for a >= 0.625, and the argument is capped at 40, where the result is 1 to
// the last bit. Both forms are computed and the one division shared. Odd by
// construction; NaN propagates; worst error 4e-16 relative.
namespace smooth_detail {

// Cephes' tanh numerator and denominator polynomials in z = x^2 (|x| < 0.625).
inline double tanhP(double z) {
  return (-9.64399179425052238628e-1 * z - 9.92877231001918586564e1) * z -
         1.61468768441708447952e3;
}
inline double tanhQ(double z) {
  return ((z + 1.12811678491632931402e2) * z + 2.23548839060100448583e3) * z +
         4.84406305325125486048e3;
}
constexpr double kTanhNearZero = 0.625;

}  // namespace smooth_detail

namespace smooth_detail {

// e^2a = up / down for a >= 0 (argument capped at 40): 2^n (Q + P) and Q - P.
struct TanhExp {
  double up, down;
};
inline TanhExp tanhExp(double a) {
  const double two_a = 2.0 * a;
  const double y = select(two_a > 40.0, 40.0, two_a);
  constexpr double kRound = 0x1.8p52;  // adding it rounds to an integer held in the low bits
  const double shifted = y * 1.4426950408889634073599 + kRound;
  const double n = shifted - kRound;
  double r = y - n * 6.93145751953125e-1;
  r -= n * 1.42860682030941723212e-6;
  const double rr = r * r;
  const double ep = r * ((1.26177193074810590878e-4 * rr + 3.02994407707441961300e-2) * rr +
                         9.99999999999999999910e-1);
  const double eq = ((3.00198505138664455042e-6 * rr + 2.52448340349684104192e-3) * rr +
                     2.27265548208155028766e-1) *
                        rr +
                    2.00000000000000000009e0;
  // Low bits of `shifted` hold n (0 <= n <= 58): (n + 1023) << 52 is 2^n.
  return {fromBits((bitsOf(shifted) + 1023) << 52) * (eq + ep), eq - ep};
}

}  // namespace smooth_detail

inline double fastTanh(double x) {
  using smooth_detail::select;
  const double a = std::abs(x);
  const double z = a * a;
  const double p = smooth_detail::tanhP(z);
  const double q = smooth_detail::tanhQ(z);
  const smooth_detail::TanhExp e = smooth_detail::tanhExp(a);
  const bool near_zero = a < smooth_detail::kTanhNearZero;
  const double ratio =
      select(near_zero, z * p, e.up - e.down) / select(near_zero, q, e.up + e.down);
  return std::copysign(select(near_zero, a + a * ratio, ratio), x);
}

// fastTanh for |x| >= 0.625 (or NaN) only: the same operations as fastTanh
// there, so the same value, without the rational branch.
inline double fastTanhFarFromZero(double x) {
  const smooth_detail::TanhExp e = smooth_detail::tanhExp(std::abs(x));
  return std::copysign((e.up - e.down) / (e.up + e.down), x);
}

// fastTanh for |x| < 0.625 only (the same operations as fastTanh there, so
// the same value): a loop whose arguments are all small can skip the
// exponential.
inline double fastTanhNearZero(double x) {
  const double a = std::abs(x);
  const double z = a * a;
  const double ratio = z * smooth_detail::tanhP(z) / smooth_detail::tanhQ(z);
  return std::copysign(a + a * ratio, x);
}

// sin(x) for the road's harmonics: k = the integer nearest x 2/pi, r = x - k pi/2
// in two parts (Cody-Waite; exact products for |k| < 2^20, beyond that an
// error of the order of x's own last bit), then the Taylor polynomials of
// sin and cos on |r| <= pi/4 (truncation below 5e-17), chosen and signed by
// k mod 4. Error: 2e-16 relative for |x| < 1; for large x a few of x's ulp
// (6.6e-10 absolute at |x| = 1e7, where x's ulp is 1.9e-9).
inline double fastSin(double x) {
  using smooth_detail::bitsOf;
  using smooth_detail::select;
  constexpr double kRound = 0x1.8p52;  // adding it rounds to an integer held in the low bits
  const double shifted = x * 6.36619772367581382433e-01 + kRound;
  const double k = shifted - kRound;
  const std::uint64_t quadrant = bitsOf(shifted);
  const double r = (x - k * 1.57079632673412561417e+00) - k * 6.07710050650619224932e-11;
  const double z = r * r;
  const double sin_r =
      r + r * z *
              (-1.0 / 6 +
               z * (1.0 / 120 +
                    z * (-1.0 / 5040 +
                         z * (1.0 / 362880 +
                              z * (-1.0 / 39916800 +
                                   z * (1.0 / 6227020800 + z * (-1.0 / 1307674368000)))))));
  const double cos_r =
      1.0 +
      z * (-0.5 +
           z * (1.0 / 24 +
                z * (-1.0 / 720 +
                     z * (1.0 / 40320 +
                          z * (-1.0 / 3628800 +
                               z * (1.0 / 479001600 +
                                    z * (-1.0 / 87178291200 + z * (1.0 / 20922789888000))))))));
  const double v = select((quadrant & 1) != 0, cos_r, sin_r);
  return select((quadrant & 2) != 0, -v, v);
}

// cos(base + d) from cos/sin of base by Taylor series in d; truncation below
// 1e-17 for |d| <= 0.25 rad, meaningless beyond (see cosOfSum).
inline double cosOfSumSeries(double cos_base, double sin_base, double d) {
  const double z = d * d;
  const double c =
      1.0 -
      z * (1.0 / 2 -
           z * (1.0 / 24 -
                z * (1.0 / 720 - z * (1.0 / 40320 - z * (1.0 / 3628800 - z * (1.0 / 479001600))))));
  const double s =
      d - d * z *
              (1.0 / 6 -
               z * (1.0 / 120 - z * (1.0 / 5040 - z * (1.0 / 362880 - z * (1.0 / 39916800)))));
  return cos_base * c - sin_base * s;
}

// Whether cosOfSumSeries is valid for d (false for NaN).
inline bool cosOfSumSeriesValid(double d) { return std::abs(d) <= 0.25; }

// cos(base + d): the series for |d| <= 0.25 rad, std::cos otherwise.
inline double cosOfSum(double base, double cos_base, double sin_base, double d) {
  if (!cosOfSumSeriesValid(d)) return std::cos(base + d);
  return cosOfSumSeries(cos_base, sin_base, d);
}

}  // namespace pc_ekf
