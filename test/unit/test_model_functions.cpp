// The inline tanh, cos and sin of smooth_functions.h against the C library.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "pc_ekf/model/smooth_functions.h"

namespace pc_ekf {
namespace {

TEST(SmoothFunctions, TanhMatchesLibraryToFewUlp) {
  double worst = 0.0;
  for (int i = -40000; i <= 40000; ++i) {
    const double x = i * 5e-4 + 1.234567e-6;  // spans both branches and the switch at 0.625
    const double ref = std::tanh(x);
    worst = std::max(worst, std::abs(fastTanh(x) - ref) / std::abs(ref));
  }
  EXPECT_LT(worst, 5e-16);
  for (double x : {1e-300, 1e-12, 3e-8, 0.6249999, 0.625, 19.0, 25.0, 800.0}) {
    EXPECT_NEAR(fastTanh(x), std::tanh(x), 4e-16 * std::tanh(x)) << x;
    EXPECT_EQ(fastTanh(-x), -fastTanh(x)) << x;  // odd, so damper forces are symmetric
  }
  EXPECT_EQ(fastTanh(0.0), 0.0);
  EXPECT_EQ(fastTanh(std::numeric_limits<double>::infinity()), 1.0);
  EXPECT_TRUE(std::isnan(fastTanh(std::numeric_limits<double>::quiet_NaN())));
}

TEST(SmoothFunctions, CosOfSumMatchesLibrary) {
  double worst = 0.0;
  for (double base : {-0.3, -0.021, 0.0, 0.021, 1.0}) {
    for (int i = -3000; i <= 3000; ++i) {
      const double d = i * 1e-4;  // beyond 0.25 the library path is taken
      const double got = cosOfSum(base, std::cos(base), std::sin(base), d);
      worst = std::max(worst, std::abs(got - std::cos(base + d)));
    }
  }
  EXPECT_LT(worst, 5e-16);
  EXPECT_TRUE(std::isnan(cosOfSum(0.1, std::cos(0.1), std::sin(0.1), std::nan(""))));
}

TEST(SmoothFunctions, SinMatchesLibrary) {
  // Near zero relative to the value; at the road's arguments (wavenumber up
  // to 31 rad/m over 100 km: |x| to 3e6) within a few of x's own ulp, which is
  // all the argument itself carries.
  double near_zero = 0.0, far = 0.0;
  for (int i = -40000; i <= 40000; ++i) {
    const double x = i * 4e-5 + 1.234567e-7;  // |x| < 1.6: both polynomials
    near_zero = std::max(near_zero, std::abs(fastSin(x) - std::sin(x)) / std::abs(std::sin(x)));
  }
  EXPECT_LT(near_zero, 5e-16);
  for (int i = 0; i <= 100000; ++i) {
    const double x = -3e6 + i * 60.000123;  // every quadrant, |x| up to 3e6
    const double ulp = std::nextafter(std::abs(x), INFINITY) - std::abs(x);
    far = std::max(far, std::abs(fastSin(x) - std::sin(x)) / ulp);
  }
  EXPECT_LT(far, 4.0);
  EXPECT_EQ(fastSin(0.0), 0.0);
  EXPECT_NEAR(fastSin(3.141592653589793), std::sin(3.141592653589793), 1e-25);
  EXPECT_TRUE(std::isnan(fastSin(std::nan(""))));
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
