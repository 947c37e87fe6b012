// A strict reader of "key = value" text files closed by an end line (the
// checkpoint's layout): every key once, '#' comments and empty lines skipped,
// nothing but empty lines after the end line. Each key is taken once; what
// is left afterwards can be listed. Errors name the file and the key.
#pragma once

#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace pc_ekf {

class KeyValueText {
 public:
  // kind names the file in messages ("checkpoint FILE: ..."); raise throws
  // the caller's exception type with the message (it must not return).
  using Raise = void (*)(const std::string& message);
  KeyValueText(const std::string& path, const std::string& kind, const std::string& end_key,
               Raise raise);

  [[noreturn]] void fail(const std::string& what) const;
  [[noreturn]] void fail(const std::string& key, const std::string& what) const;

  // The value's whitespace-separated tokens; the key is consumed.
  std::vector<std::string> tokens(const std::string& key);
  std::string text(const std::string& key);  // exactly one token

  double real(const std::string& key, const std::string& token) const;  // finite
  std::uint64_t whole(const std::string& key, const std::string& token, std::uint64_t max) const;
  void count(const std::string& key, const std::vector<std::string>& t, std::size_t n) const;
  double real(const std::string& key);  // a one-token value
  int integer(const std::string& key);  // a one-token value in [0, INT_MAX]

  std::vector<std::string> remainingKeys() const;  // sorted
  const std::string& endValue() const { return end_value_; }

 private:
  std::string path_, kind_;
  Raise raise_;
  std::string end_value_;
  std::map<std::string, std::string> values_;
};

}  // namespace pc_ekf
