// The CSV number text (appendG17) against std::to_chars(general, 17), which
// writes printf's %.17g: the same bytes on values of every kind, including
// exact ties at the 18th digit (rounded half to even) and the range edges
// where appendG17 hands over to to_chars.
#include <gtest/gtest.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <string>

#include "pc_ekf/io/number_text.h"

namespace pc_ekf {
namespace {

std::string reference(double v) {
  char text[40];
  const auto r = std::to_chars(text, text + sizeof(text), v, std::chars_format::general, 17);
  return std::string(text, r.ptr);
}

int mismatches = 0;
void expectG17(double v) {
  std::string text;
  appendG17(text, v);
  if (text != reference(v) && ++mismatches <= 10) {
    ADD_FAILURE() << "appendG17(" << std::hexfloat << v << ") = " << text << ", %.17g "
                  << reference(v);
  }
}

TEST(NumberText, AppendG17WritesPrintfsDigitsForEveryKindOfValue) {
  std::mt19937_64 rng(7);
  // Any bit pattern: every exponent, subnormals, infinities, NaNs.
  for (int i = 0; i < 500000; ++i) {
    const std::uint64_t bits = rng();
    double v;
    std::memcpy(&v, &bits, sizeof v);
    expectG17(v);
  }
  // Log-uniform over the CSVs' magnitudes and past the range's edges, with
  // each value's neighbour.
  std::uniform_real_distribution<double> exponent(-8.0, 18.0);
  for (int i = 0; i < 1000000; ++i) {
    const double v = std::pow(10.0, exponent(rng)) * ((rng() & 1) ? -1.0 : 1.0);
    expectG17(v);
    expectG17(std::nextafter(v, 0.0));
  }
  // Short binary fractions: many are exact ties at the 18th digit.
  for (int i = 0; i < 500000; ++i) {
    expectG17(std::ldexp(static_cast<double>(rng() >> (11 + rng() % 40)), -static_cast<int>(rng() % 64)));
  }
  for (long k = 1; k < 200000; ++k) {
    expectG17(k * 0.25);
    expectG17(1e15 + k * 0.25);  // ulp 0.25: 1234567890123456.25 is a tie
    expectG17(-k / 1024.0);
  }
  // Powers of ten and their neighbours, zeros, the ends of the range.
  for (int p = -8; p <= 18; ++p) {
    const double v = std::pow(10.0, p);
    for (double w : {v, -v, std::nextafter(v, 0.0), std::nextafter(v, 1e300), 9.9999999999999999 * v}) {
      expectG17(w);
    }
  }
  for (double v : {0.0, -0.0, 1e-6, 1e17, std::numeric_limits<double>::max(),
                   std::numeric_limits<double>::denorm_min(), std::numeric_limits<double>::infinity(),
                   std::numeric_limits<double>::quiet_NaN(), 0.1, 1.0 / 3.0, 223.20723612738544}) {
    expectG17(v);
  }
  EXPECT_EQ(mismatches, 0);
  std::string text;
  appendG17(text, 0.1);
  EXPECT_EQ(text, "0.10000000000000001");
  text.clear();
  appendG17(text, 1234567890123456.25);  // tie: the even digit
  EXPECT_EQ(text, "1234567890123456.2");
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
