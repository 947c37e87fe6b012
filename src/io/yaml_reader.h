// Strict reading of one YAML map: every value is checked, every key must be
// known, and errors name the file, the full key path, the value and what was
// expected.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include "pc_ekf/io/config_error.h"

namespace pc_ekf {

// One key a YamlMapReader was asked for: its full path (list items as
// `seq[3]`), what was read (number, integer, unsigned, text, number list,
// text list, number or list, map, list), the value it held when asked (the
// default when the key is absent) and, for numbers, its accepted range.
struct YamlKeyRead {
  std::string path;
  std::string kind;
  std::string value;
  std::string domain;
};

// While one lives, every YamlMapReader on this thread appends the keys it is
// asked for (the configuration schema's test: src/io/config_schema.h).
class YamlKeyLog {
 public:
  YamlKeyLog();
  ~YamlKeyLog();
  YamlKeyLog(const YamlKeyLog&) = delete;
  YamlKeyLog& operator=(const YamlKeyLog&) = delete;
  const std::vector<YamlKeyRead>& reads() const { return reads_; }
  // The log of this thread (nullptr: none).
  static YamlKeyLog* active();
  void add(YamlKeyRead read) { reads_.push_back(std::move(read)); }

 private:
  std::vector<YamlKeyRead> reads_;
  YamlKeyLog* previous_;
};

// A number range as the schema writes it: "[0, 1]", "(0, inf)", "any".
std::string rangeDomainText(double min, double max, bool min_exclusive);

class YamlMapReader {
 public:
  // `node` must be a map (or absent/null, read as empty); `path` is its key path
  // ("" for the root), `source` the file name.
  YamlMapReader(const YAML::Node& node, std::string path, std::string source);

  bool has(const std::string& key) const;
  bool isMap(const std::string& key) const;  // present and a map
  bool isSequence(const std::string& key) const;  // present and a list
  bool empty() const { return !node_.IsMap() || node_.size() == 0; }
  YamlMapReader map(const std::string& key);  // absent -> empty map
  YAML::Node sequence(const std::string& key);  // absent -> null node

  // Each reads `key` if present into `value` (which holds the default).
  void number(const std::string& key, double& value, double min, double max,
              bool min_exclusive = false);
  void integer(const std::string& key, int& value, int min, int max);
  void unsignedInteger(const std::string& key, std::uint64_t& value);
  void text(const std::string& key, std::string& value);
  void numberList(const std::string& key, std::vector<double>& value, std::size_t size_min,
                  std::size_t size_max);
  void textList(const std::string& key, std::vector<std::string>& value);
  // A list of exactly `size` numbers in [min, max], or one such number for
  // all; an empty list leaves `value` as it is.
  void numberPerItem(const std::string& key, std::vector<double>& value, std::size_t size,
                     double min, double max);

  // Throws for keys present but never read.
  void finish() const;

  [[noreturn]] void fail(const std::string& key, const std::string& value,
                         const std::string& expected) const;
  std::string keyPath(const std::string& key) const;
  const std::string& source() const { return source_; }

 private:
  void note(const std::string& key, const std::string& kind, std::string value,
            std::string domain = "");
  YAML::Node node_;
  std::string path_;
  std::string source_;
  std::set<std::string> read_;
};

// Scalar text of a node for messages ("[list]" / "{map}" for containers).
std::string yamlValueText(const YAML::Node& node);

}  // namespace pc_ekf
