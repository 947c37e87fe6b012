#include "pc_ekf/io/key_value_text.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>

#include "pc_ekf/io/number_text.h"

namespace pc_ekf {

KeyValueText::KeyValueText(const std::string& path, const std::string& kind,
                           const std::string& end_key, Raise raise)
    : path_(path), kind_(kind), raise_(raise) {
  std::ifstream in(path);
  if (!in) fail("cannot open the " + kind_ + " file (" + std::string(std::strerror(errno)) + ")");
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  // Checked first: a cut-off file would otherwise fail on its last, partial line.
  const std::string end_prefix = end_key + " = ";
  const auto end_line = std::find_if(lines.begin(), lines.end(), [&](const std::string& l) {
    return l.rfind(end_prefix, 0) == 0;
  });
  if (end_line == lines.end()) {
    fail("no '" + end_key + "' line: the file is truncated or not a " + kind_);
  }
  end_value_ = end_line->substr(end_prefix.size());
  if (std::any_of(end_line + 1, lines.end(), [](const std::string& l) { return !l.empty(); })) {
    fail("text after the '" + end_key + "' line");
  }
  for (auto it = lines.begin(); it != end_line; ++it) {
    const std::string& line = *it;
    const std::string where = "line " + std::to_string(it - lines.begin() + 1);
    if (line.empty() || line[0] == '#') continue;
    const std::size_t eq = line.find(" = ");
    if (eq == std::string::npos) {
      fail(where + ": expected 'key = value', got '" + line.substr(0, 60) + "'");
    }
    const std::string key = line.substr(0, eq);
    if (!values_.emplace(key, line.substr(eq + 3)).second) {
      fail(where + ": key '" + key + "' appears twice");
    }
  }
}

void KeyValueText::fail(const std::string& what) const {
  raise_(kind_ + " " + path_ + ": " + what);
  throw std::logic_error("KeyValueText: raise returned");
}

void KeyValueText::fail(const std::string& key, const std::string& what) const {
  fail("key '" + key + "': " + what);
}

std::vector<std::string> KeyValueText::tokens(const std::string& key) {
  const auto it = values_.find(key);
  if (it == values_.end()) fail(key, "missing");
  std::istringstream in(it->second);
  values_.erase(it);
  std::vector<std::string> out;
  for (std::string t; in >> t;) out.push_back(t);
  if (out.empty()) fail(key, "empty value");
  return out;
}

std::string KeyValueText::text(const std::string& key) {
  const auto t = tokens(key);
  if (t.size() != 1) fail(key, "expected one word, got " + std::to_string(t.size()));
  return t[0];
}

double KeyValueText::real(const std::string& key, const std::string& token) const {
  const auto v = parseFiniteDouble(token);
  if (!v) fail(key, "'" + token + "' is not a finite number");
  return *v;
}

std::uint64_t KeyValueText::whole(const std::string& key, const std::string& token,
                                  std::uint64_t max) const {
  const auto v = parseWholeNumber(token, max);
  if (!v) fail(key, "'" + token + "' is not an integer in [0, " + std::to_string(max) + "]");
  return *v;
}

void KeyValueText::count(const std::string& key, const std::vector<std::string>& t,
                         std::size_t n) const {
  if (t.size() != n) {
    fail(key, "expected " + std::to_string(n) + " values, got " + std::to_string(t.size()));
  }
}

double KeyValueText::real(const std::string& key) {
  const auto t = tokens(key);
  count(key, t, 1);
  return real(key, t[0]);
}

int KeyValueText::integer(const std::string& key) {
  const auto t = tokens(key);
  count(key, t, 1);
  return static_cast<int>(whole(key, t[0], std::numeric_limits<int>::max()));
}

std::vector<std::string> KeyValueText::remainingKeys() const {
  std::vector<std::string> keys;
  for (const auto& kv : values_) keys.push_back(kv.first);
  return keys;
}

}  // namespace pc_ekf
