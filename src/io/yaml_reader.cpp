#include "pc_ekf/io/yaml_reader.h"

#include <cmath>
#include <limits>
#include <sstream>

#include "pc_ekf/io/number_text.h"

namespace pc_ekf {

namespace {
thread_local YamlKeyLog* active_log = nullptr;

template <typename T, typename Text>
std::string listText(const std::vector<T>& values, Text text) {
  std::string out = "[";
  for (std::size_t i = 0; i < values.size(); ++i) out += (i ? ", " : "") + text(values[i]);
  return out + "]";
}
}  // namespace

YamlKeyLog::YamlKeyLog() : previous_(active_log) { active_log = this; }
YamlKeyLog::~YamlKeyLog() { active_log = previous_; }
YamlKeyLog* YamlKeyLog::active() { return active_log; }

std::string rangeDomainText(double min, double max, bool min_exclusive) {
  const double inf = std::numeric_limits<double>::infinity();
  if (min == -inf && max == inf) return "any";
  return (min_exclusive ? "(" : "[") + (min == -inf ? "-inf" : roundTripText(min)) + ", " +
         (max == inf ? "inf)" : roundTripText(max) + "]");
}

void YamlMapReader::note(const std::string& key, const std::string& kind, std::string value,
                         std::string domain) {
  if (!read_.insert(key).second) return;  // noted when first asked for
  if (YamlKeyLog* log = YamlKeyLog::active()) {
    log->add({keyPath(key), kind, std::move(value), std::move(domain)});
  }
}

std::string yamlValueText(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "(empty)";
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  if (node.IsSequence()) return "a list of " + std::to_string(node.size());
  return "a map";
}

YamlMapReader::YamlMapReader(const YAML::Node& node, std::string path, std::string source)
    : node_(node), path_(std::move(path)), source_(std::move(source)) {
  if (node_.IsDefined() && !node_.IsNull() && !node_.IsMap()) {
    throw ConfigError(source_ + ": key '" + (path_.empty() ? "(root)" : path_) + "': value " +
                      yamlValueText(node_) + " invalid, expected a map of keys");
  }
}

std::string YamlMapReader::keyPath(const std::string& key) const {
  return path_.empty() ? key : path_ + "." + key;
}

void YamlMapReader::fail(const std::string& key, const std::string& value,
                         const std::string& expected) const {
  throw ConfigError(source_ + ": key '" + keyPath(key) + "': value " + value + " invalid, expected " +
                    expected);
}

bool YamlMapReader::has(const std::string& key) const {
  return node_.IsMap() && node_[key].IsDefined() && !node_[key].IsNull();
}

bool YamlMapReader::isMap(const std::string& key) const { return has(key) && node_[key].IsMap(); }

YamlMapReader YamlMapReader::map(const std::string& key) {
  note(key, "map", "{}");
  if (!has(key)) return YamlMapReader(YAML::Node(), keyPath(key), source_);
  const YAML::Node child = node_[key];
  if (!child.IsMap()) fail(key, yamlValueText(child), "a map of keys");
  return YamlMapReader(child, keyPath(key), source_);
}

bool YamlMapReader::isSequence(const std::string& key) const {
  return has(key) && node_[key].IsSequence();
}

YAML::Node YamlMapReader::sequence(const std::string& key) {
  note(key, "list", "[]");
  if (!has(key)) return YAML::Node();
  const YAML::Node child = node_[key];
  if (!child.IsSequence()) fail(key, yamlValueText(child), "a list");
  return child;
}

namespace {

bool parseDouble(const YAML::Node& n, double& out) {
  if (!n.IsScalar()) return false;
  std::string s = n.Scalar();
  // YAML spellings of infinity/NaN are refused below anyway; accept plain numbers only.
  std::istringstream in(s);
  in.imbue(std::locale::classic());
  in >> out;
  return !in.fail() && in.eof();
}

std::string rangeText(double min, double max, bool min_exclusive) {
  std::ostringstream o;
  const double inf = std::numeric_limits<double>::infinity();
  if (max == inf && min == 0.0 && min_exclusive) return "a positive number";
  if (max == inf && min == 0.0) return "a non-negative number";
  if (max == inf && min == -inf) return "a finite number";
  o << "a number in " << (min_exclusive ? "(" : "[") << min << ", " << max << "]";
  return o.str();
}

}  // namespace

void YamlMapReader::number(const std::string& key, double& value, double min, double max,
                           bool min_exclusive) {
  note(key, "number", roundTripText(value), rangeDomainText(min, max, min_exclusive));
  if (!has(key)) return;
  double v = 0.0;
  const YAML::Node n = node_[key];
  const bool ok = parseDouble(n, v) && std::isfinite(v) && v <= max &&
                  (min_exclusive ? v > min : v >= min);
  if (!ok) fail(key, yamlValueText(n), rangeText(min, max, min_exclusive));
  value = v;
}

void YamlMapReader::integer(const std::string& key, int& value, int min, int max) {
  note(key, "integer", std::to_string(value),
       "[" + std::to_string(min) + ", " + std::to_string(max) + "]");
  if (!has(key)) return;
  const YAML::Node n = node_[key];
  double v = 0.0;
  if (!parseDouble(n, v) || v != std::floor(v) || v < min || v > max) {
    fail(key, yamlValueText(n),
         "an integer in [" + std::to_string(min) + ", " + std::to_string(max) + "]");
  }
  value = static_cast<int>(v);
}

void YamlMapReader::unsignedInteger(const std::string& key, std::uint64_t& value) {
  note(key, "unsigned", std::to_string(value), "[0, 2^64)");
  if (!has(key)) return;
  const YAML::Node n = node_[key];
  const std::string s = n.IsScalar() ? n.Scalar() : "";
  if (s.empty() || s.find_first_not_of("0123456789") != std::string::npos || s.size() > 19) {
    fail(key, yamlValueText(n), "a non-negative integer");
  }
  value = std::stoull(s);
}

void YamlMapReader::text(const std::string& key, std::string& value) {
  note(key, "text", value.empty() ? "\"\"" : value);
  if (!has(key)) return;
  const YAML::Node n = node_[key];
  if (!n.IsScalar()) fail(key, yamlValueText(n), "a text value");
  value = n.Scalar();
}

void YamlMapReader::numberList(const std::string& key, std::vector<double>& value,
                               std::size_t size_min, std::size_t size_max) {
  note(key, "number list", listText(value, roundTripText));
  const YAML::Node seq = sequence(key);
  if (!seq.IsDefined() || seq.IsNull()) return;
  const std::string expected =
      size_min == size_max ? "a list of " + std::to_string(size_min) + " numbers"
                           : "a list of " + std::to_string(size_min) + " to " +
                                 std::to_string(size_max) + " numbers";
  if (seq.size() < size_min || seq.size() > size_max) fail(key, yamlValueText(seq), expected);
  std::vector<double> out;
  for (const auto& item : seq) {
    double v = 0.0;
    if (!parseDouble(item, v) || !std::isfinite(v)) {
      fail(key + "[" + std::to_string(out.size()) + "]", yamlValueText(item), "a finite number");
    }
    out.push_back(v);
  }
  value = out;
}

void YamlMapReader::numberPerItem(const std::string& key, std::vector<double>& value,
                                  std::size_t size, double min, double max) {
  note(key, "number or list", listText(value, roundTripText), rangeDomainText(min, max, false));
  if (!has(key)) return;
  const YAML::Node n = node_[key];
  if (n.IsScalar()) {
    double v = 0.0;
    number(key, v, min, max);
    value.assign(size, v);
    return;
  }
  if (n.IsSequence() && n.size() == 0) return;
  if (n.IsSequence() && n.size() != size) {
    fail(key, yamlValueText(n), "a list of " + std::to_string(size) + " numbers or one number");
  }
  std::vector<double> out;
  numberList(key, out, size, size);
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (!(out[i] >= min && out[i] <= max)) {
      fail(key + "[" + std::to_string(i) + "]", std::to_string(out[i]), rangeText(min, max, false));
    }
  }
  value = out;
}

void YamlMapReader::textList(const std::string& key, std::vector<std::string>& value) {
  note(key, "text list", listText(value, [](const std::string& t) { return t; }));
  const YAML::Node seq = sequence(key);
  if (!seq.IsDefined() || seq.IsNull()) return;
  std::vector<std::string> out;
  for (const auto& item : seq) {
    if (!item.IsScalar()) {
      fail(key + "[" + std::to_string(out.size()) + "]", yamlValueText(item), "a text value");
    }
    out.push_back(item.Scalar());
  }
  value = out;
}

void YamlMapReader::finish() const {
  if (!node_.IsMap()) return;
  for (const auto& kv : node_) {
    // A null, list or map key (`~: 1`, `? [a, b]: 1`) is no key of the schema;
    // as<std::string>() would throw YAML::TypedBadConversion (found by fuzzing).
    if (!kv.first.IsScalar()) {
      throw ConfigError(source_ + ": key '" + (path_.empty() ? "(root)" : path_) +
                        "': a key must be a text value, got " + yamlValueText(kv.first));
    }
    const std::string key = kv.first.Scalar();
    if (!read_.count(key)) {
      throw ConfigError(source_ + ": key '" + keyPath(key) + "': unknown key (value " +
                        yamlValueText(kv.second) + "); see config/speed_bump.yaml for the schema");
    }
  }
}

}  // namespace pc_ekf
