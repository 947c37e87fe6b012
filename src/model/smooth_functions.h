// Inline tanh and cos for the damper law and the roll lever (SPEC §1.2, §1.4): glibc's
// calls were 2/3 of the RK4 cost (ENGINEERING.md, Numerics). Accuracy: a few ulp.
#pragma once

#include <cmath>

namespace pc_ekf {

// Cephes tanh: rational form near 0 (keeps relative accuracy and tanh(0) = 0),
// 1 - 2 / (exp(2|x|) + 1) elsewhere (no cancellation there). NaN propagates.
inline double fastTanh(double x) {
  const double a = std::abs(x);
  if (a < 0.625) {
    const double z = x * x;
    const double p =
        (-9.64399179425052238628e-1 * z - 9.92877231001918586564e1) * z - 1.61468768441708447952e3;
    const double q = ((z + 1.12811678491632931402e2) * z + 2.23548839060100448583e3) * z +
                     4.84406305325125486048e3;
    return x + x * (z * p / q);
  }
  return std::copysign(1.0 - 2.0 / (std::exp(2.0 * a) + 1.0), x);
}

// cos(base + d) from cos/sin of base, with Taylor series in d for |d| <= 0.25 rad
// (truncation below 1e-17); std::cos otherwise.
inline double cosOfSum(double base, double cos_base, double sin_base, double d) {
  if (!(std::abs(d) <= 0.25)) return std::cos(base + d);
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

}  // namespace pc_ekf
