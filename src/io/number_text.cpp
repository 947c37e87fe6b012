#include "pc_ekf/io/number_text.h"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>

namespace pc_ekf {

namespace {

constexpr char kDigitPairs[] =
    "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
    "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
    "8081828384858687888990919293949596979899";

// %.17g of v where |v| is in [1e-6, 1e17) (the CSVs' numbers), by exact
// 128-bit arithmetic: the 17 significant digits are the integer part of
// m 10^s / 2^-e (v = m 2^e, s = 16 - x), rounded half to even on the exact
// remainder, as printf and std::to_chars round; then %g's layout. False
// (nothing written) outside that range, where appendG17 asks std::to_chars.
// About 60 % of to_chars' time (96 -> 58 ns); test_io_number_text compares
// the two on 4e6 values.
bool exactG17(double v, char* out, char** end) {
  std::uint64_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  const int biased = static_cast<int>((bits >> 52) & 0x7ff);
  if (biased == 0 || biased == 0x7ff) return false;  // zero, subnormal, inf, nan
  const double a = v < 0 ? -v : v;
  if (!(a >= 1e-6 && a < 1e17)) return false;
  using U128 = unsigned __int128;
  static const U128* const pow10 = [] {
    static U128 p[23];
    p[0] = 1;
    for (int i = 1; i < 23; ++i) p[i] = p[i - 1] * 10;
    return p;
  }();
  const std::uint64_t m = (bits & ((std::uint64_t(1) << 52) - 1)) | (std::uint64_t(1) << 52);
  const int e = biased - 1075;  // v = m 2^e
  // Decimal exponent x (10^x <= a < 10^(x+1)): estimated from the binary
  // exponent (x or x - 1), then corrected by the exact integer part of
  // a 10^(16 - x), which must have 17 digits.
  int x = ((biased - 1023) * 78913) >> 18;
  U128 digits = 0, rem = 0, halfway = 0;
  const int shift = -e;
  if (shift >= 127) return false;
  for (int attempt = 0;; ++attempt) {
    const int s = 16 - x;
    if (attempt == 3 || s < 0 || s > 22) return false;
    const U128 p = U128(m) * pow10[s];
    if (shift <= 0) {
      digits = p << -shift;
      rem = 0;
    } else {
      digits = p >> shift;
      rem = p & ((U128(1) << shift) - 1);
      halfway = U128(1) << (shift - 1);
    }
    if (digits < pow10[16]) {
      --x;
    } else if (digits >= pow10[17]) {
      ++x;
    } else {
      break;
    }
  }
  if (shift > 0 && (rem > halfway || (rem == halfway && (digits & 1)))) ++digits;
  if (digits == pow10[17]) {
    digits = pow10[16];
    ++x;
  }
  // The 17 digits two at a time (9 + 8: each half fits 32 bits).
  char d[17];
  {
    const std::uint64_t dd = static_cast<std::uint64_t>(digits);
    std::uint32_t hi = static_cast<std::uint32_t>(dd / 100000000u);  // 9 digits
    std::uint32_t lo = static_cast<std::uint32_t>(dd % 100000000u);  // 8 digits
    for (int i = 15; i >= 9; i -= 2) {
      std::memcpy(d + i, kDigitPairs + 2 * (lo % 100), 2);
      lo /= 100;
    }
    for (int i = 7; i >= 1; i -= 2) {
      std::memcpy(d + i, kDigitPairs + 2 * (hi % 100), 2);
      hi /= 100;
    }
    d[0] = static_cast<char>('0' + hi);
  }
  int len = 17;
  while (len > 1 && d[len - 1] == '0') --len;  // trailing zeros go (%g)
  char* o = out;
  if (v < 0) *o++ = '-';
  if (x >= -4 && x < 17) {
    if (x >= 0) {
      const int int_digits = x + 1;
      for (int i = 0; i < int_digits; ++i) *o++ = i < len ? d[i] : '0';
      if (len > int_digits) {
        *o++ = '.';
        for (int i = int_digits; i < len; ++i) *o++ = d[i];
      }
    } else {
      *o++ = '0';
      *o++ = '.';
      for (int i = 0; i < -x - 1; ++i) *o++ = '0';
      for (int i = 0; i < len; ++i) *o++ = d[i];
    }
  } else {
    *o++ = d[0];
    if (len > 1) {
      *o++ = '.';
      for (int i = 1; i < len; ++i) *o++ = d[i];
    }
    *o++ = 'e';
    int ex = x;
    *o++ = ex < 0 ? '-' : '+';
    if (ex < 0) ex = -ex;
    if (ex >= 100) *o++ = static_cast<char>('0' + ex / 100);
    *o++ = static_cast<char>('0' + (ex / 10) % 10);
    *o++ = static_cast<char>('0' + ex % 10);
  }
  *end = o;
  return true;
}

}  // namespace

std::string roundTripText(double v) {
  char text[40];
  const auto r = std::to_chars(text, text + sizeof(text), v);
  return std::string(text, r.ptr);
}

char* writeG17(char* out, double v) {
  if (v == 0.0) {  // most of an affine expansion's coefficients: to_chars' slow path
    if (std::signbit(v)) *out++ = '-';
    *out++ = '0';
    return out;
  }
  char* end = nullptr;
  if (!exactG17(v, out, &end)) {
    end = std::to_chars(out, out + kG17Chars, v, std::chars_format::general, 17).ptr;
  }
  return end;
}

void appendG17(std::string& out, double v) {
  char text[kG17Chars];
  out.append(text, static_cast<std::size_t>(writeG17(text, v) - text));  // (pointer, count): no replace path
}

std::optional<double> parseFiniteDouble(const std::string& token) {
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(token.c_str(), &end);
  if (end == token.c_str() || *end != '\0' || !std::isfinite(v)) return std::nullopt;
  return v;
}

std::optional<std::uint64_t> parseWholeNumber(const std::string& token, std::uint64_t max) {
  char* end = nullptr;
  errno = 0;
  const unsigned long long v = std::strtoull(token.c_str(), &end, 10);
  if (token.empty() || token[0] == '-' || end == token.c_str() || *end != '\0' || errno == ERANGE ||
      v > max) {
    return std::nullopt;
  }
  return v;
}

}  // namespace pc_ekf
