#include "pc_ekf/io/number_text.h"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>

namespace pc_ekf {

std::string roundTripText(double v) {
  char text[40];
  const auto r = std::to_chars(text, text + sizeof(text), v);
  return std::string(text, r.ptr);
}

void appendG17(std::string& out, double v) {
  char text[40];
  const auto r = std::to_chars(text, text + sizeof(text), v, std::chars_format::general, 17);
  out.append(text, r.ptr);
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
