// The configuration schema as documented: one entry per key of the YAML that
// parseConfig (estimator_config.h) accepts. docs/configuration.md's key
// tables are generated from it, and test_io_config_schema checks it against
// the parser: every key the parser asks for is here, every key here is asked
// for, and each default and number range is the one the parser holds.
//
// To add a key: read it in estimator_config.cpp (a YamlMapReader call), add
// its line to the table in config_schema.cpp, then regenerate the docs with
//   PC_EKF_UPDATE_DOCS=1 .build/catkin_ws/devel/lib/pc_ekf/test_io_config_schema
// and list it in config/speed_bump.yaml (set, or in a comment).
#pragma once

#include <string>
#include <vector>

namespace pc_ekf {

struct ConfigKey {
  // Dotted key path; a list item is `[i]`, a name the model type decides is
  // `<name>` (a model parameter) or `<suspension>` (a suspension's key).
  const char* path;
  // number, integer, unsigned, bool, choice, text, numbers (a list), names
  // (a list of text), list (of maps), map; "number or numbers" for either.
  const char* type;
  // The value when the key is absent, as the parser holds it ("required":
  // none). Text after " (" is a note.
  const char* default_value;
  // The accepted values; numbers as "[min, max]" ("(" excludes the bound),
  // a note after " (".
  const char* domain;
  const char* meaning;  // one line
};

// Every key, in the order of docs/configuration.md.
const std::vector<ConfigKey>& configSchema();

// The first component of a key path (`filter` for `filter.enkf.seed`,
// `uncertain` for `uncertain[i].name`).
std::string configSection(const std::string& path);

// The Markdown table (key | type | default | domain | meaning) of the keys in
// the given top-level sections, in table order.
std::string configSchemaMarkdown(const std::vector<std::string>& sections);

}  // namespace pc_ekf
