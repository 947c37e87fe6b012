// The configuration schema (src/io/config_schema.cpp) against the parser:
// every key the parser asks for is in the table, every key in the table is
// asked for, the table's types, defaults and number ranges are the parser's;
// docs/configuration.md carries the generated tables and config/speed_bump.yaml
// lists every key. PC_EKF_UPDATE_DOCS=1 rewrites configuration.md's tables.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include "pc_ekf/io/config_schema.h"
#include "pc_ekf/io/estimator_config.h"
#include "pc_ekf/io/yaml_reader.h"

namespace pc_ekf {
namespace {

// Nothing but what the parser insists on: every default in force.
const char* kDefaults =
    "uncertain:\n"
    "  - {name: added_mass, relative_range: 0.5}\n"
    "  - {name: added_mass_position, relative_range: 0.25}\n";

// Every branch that reads keys of its own: tolerances (number and map), a
// course of each segment type (speed_bump, sine, rest, iso8608, turn, brake, accelerate,
// lane_change, slalom), a truth
// road, vehicle and schedule (xi and values).
const char* kBranches =
    "uncertain:\n"
    "  - {name: added_mass, nominal: 200.0, relative_range: 0.5}\n"
    "tolerances:\n"
    "  spring_linear_left: 0.1\n"
    "  damping_left: {relative_range: 0.2, germ: {family: beta}}\n"
    "collocation: {points: 40}\n"
    "road:\n"
    "  source: course\n"
    "  course:\n"
    "    - {type: speed_bump}\n"
    "    - {type: sine, duration: 1.0}\n"
    "    - {type: rest, duration: 1.0}\n"
    "    - {type: iso8608, duration: 1.0, speed_kmh: 54.0, class: C, seed: 7, correlation: 0.5}\n"
    "    - {type: turn, duration: 2.0, radius: -30.0, ramp: 0.5}\n"
    "    - {type: lane_change, duration: 2.0, lateral_acceleration: 4.0, surface: iso8608}\n"
    "    - {type: slalom, duration: 2.0, frequency: 0.5}\n"
    "    - {type: brake, duration: 2.0, speed_kmh: 72.0, deceleration: 4.0, surface: iso8608}\n"
    "    - {type: accelerate, duration: 2.0, speed_kmh: 20.0, acceleration: 2.0}\n"
    "vehicle:\n"
    "  motion_ratio_left: 0.8\n"
    "  motion_ratio_right: 0.8\n"
    "  damper_table_left: {bump: [[0.5, 400]], rebound: [[0.5, 900]]}\n"
    "  damper_table_right: {bump: [[0.5, 400]], rebound: [[0.5, 900]]}\n"
    "truth:\n"
    "  vehicle: {bar_mass: 590.0}\n"
    "  road: {source: sine}\n"
    "  schedule:\n"
    "    - {time: 1.0, xi: [0.1]}\n"
    "    - {time: 2.0, values: {added_mass: 240.0}}\n";

// The datasheet forms not in kBranches (the shared damper table).
const char* kDatasheet =
    "vehicle:\n"
    "  motion_ratio_left: 0.8\n"
    "  motion_ratio_right: 0.8\n"
    "  damper_table: {bump: [[0.5, 400]], rebound: [[0.5, 900]]}\n"
    "uncertain:\n"
    "  - {name: added_mass, relative_range: 0.5}\n";

const char* kFullCar =
    "model: {type: full_car}\n"
    "uncertain:\n"
    "  - {name: added_mass, relative_range: 0.5}\n";

// A manoeuvre on a measured profile (its file must exist to be read).
std::string measuredSurface() {
  const std::string file = ::testing::TempDir() + "/schema_profile.csv";
  std::ofstream(file) << "s,left,right\n0,0,0\n100,0.01,0.02\n";
  return "uncertain:\n"
         "  - {name: added_mass, relative_range: 0.5}\n"
         "road:\n"
         "  source: course\n"
         "  course:\n"
         "    - {type: slalom, duration: 2.0, speed_kmh: 36.0, surface: profile, file: " + file +
         ", start: 5.0}\n";
}

// Read before the YamlMapReader sees the config (mergeVehicleFile).
const std::set<std::string> kReadBeforeTheReader = {"vehicle_file"};

std::vector<YamlKeyRead> readsOf(const std::string& yaml) {
  YamlKeyLog log;
  parseConfigString(yaml, "schema_test.yaml");
  return log.reads();
}

bool startsWith(const std::string& s, const std::string& prefix) {
  return s.compare(0, prefix.size(), prefix) == 0;
}

// A read's path as the table writes it: `[i]` for list items, placeholders
// for the names a model type decides.
std::string tablePath(const std::string& read_path) {
  const std::string p = std::regex_replace(read_path, std::regex("\\[[0-9]+\\]"), "[i]");
  const auto after = [&](const std::string& prefix) {
    return startsWith(p, prefix) && p.size() > prefix.size();
  };
  if (after("vehicle.")) {
    // The datasheet forms (one row each; <side> a suffix of spring_linear_).
    static const std::regex sided(
        "vehicle\\.(motion_ratio|damper_motion_ratio|spring_rate|spring_cubic_rate|damper_rate)_"
        "[a-z]+");
    static const std::regex table("vehicle\\.damper_table_[a-z]+(\\..*)?");
    static const std::set<std::string> own = {"vehicle.damper_table", "vehicle.wheel_track",
                                              "vehicle.spring_track", "vehicle.wheelbase",
                                              "vehicle.front_axle_load_share"};
    std::smatch m;
    if (std::regex_match(p, m, sided)) return "vehicle." + m[1].str() + "_<side>";
    if (std::regex_match(p, m, table)) {
      return m[1].str().empty() ? "vehicle.damper_table_<side>" : "vehicle.damper_table" + m[1].str();
    }
    if (own.count(p) || startsWith(p, "vehicle.damper_table.")) return p;
    return "vehicle.<name>";
  }
  if (after("truth.vehicle.")) return "truth.vehicle.<name>";
  if (after("truth.schedule[i].values.")) return "truth.schedule[i].values.<name>";
  if (after("node.joints.")) return "node.joints.<suspension>";
  if (after("tolerances.")) {
    const std::size_t dot = p.find('.', 11);
    return "tolerances.<name>" + (dot == std::string::npos ? "" : p.substr(dot));
  }
  // A course segment's own rows; the other keys are road.speed_bump's or road.sine's.
  static const std::set<std::string> segment_rows = {
      "road.course[i].type",  "road.course[i].duration", "road.course[i].speed_kmh",
      "road.course[i].class", "road.course[i].seed",     "road.course[i].correlation",
      "road.course[i].lateral_acceleration", "road.course[i].radius", "road.course[i].ramp",
      "road.course[i].frequency", "road.course[i].surface", "road.course[i].deceleration",
      "road.course[i].acceleration", "road.course[i].file", "road.course[i].start"};
  if (after("road.course[i].") && !segment_rows.count(p)) {
    return "road.course[i].<speed_bump or sine key>";
  }
  return p;
}

struct Recorded {
  std::set<std::string> kinds;
  bool has_children = false;
};

// Table path -> what was read there, over every config given.
std::map<std::string, Recorded> recorded(const std::vector<std::string>& yamls) {
  std::map<std::string, Recorded> out;
  for (const auto& yaml : yamls) {
    for (const YamlKeyRead& r : readsOf(yaml)) {
      // truth.road holds a road: section, whose keys are documented there.
      if (startsWith(r.path, "truth.road.")) continue;
      out[tablePath(r.path)].kinds.insert(r.kind);
    }
  }
  for (auto& [path, rec] : out) {
    for (const auto& [other, unused] : out) {
      (void)unused;
      if (startsWith(other, path + ".") || startsWith(other, path + "[")) rec.has_children = true;
    }
  }
  return out;
}

// A key of the schema: not a map holding keys read on their own.
bool isKey(const Recorded& r) {
  return !r.has_children || r.kinds.size() > 1 || !r.kinds.count("map");
}

std::map<std::string, const ConfigKey*> tableByPath() {
  std::map<std::string, const ConfigKey*> out;
  for (const ConfigKey& k : configSchema()) {
    EXPECT_TRUE(out.emplace(k.path, &k).second) << "twice in the table: " << k.path;
  }
  return out;
}

// `documented` is `code`, or `code` followed by a note " (...)".
bool sameUpToNote(const std::string& documented, const std::string& code) {
  return documented == code || startsWith(documented, code + " (");
}

TEST(ConfigSchema, EveryKeyTheParserAcceptsIsInTheTable) {
  const auto table = tableByPath();
  for (const auto& [path, rec] : recorded({kDefaults, kBranches, kFullCar, kDatasheet, measuredSurface()})) {
    if (!isKey(rec)) continue;
    EXPECT_TRUE(table.count(path))
        << "the parser accepts '" << path << "' but src/io/config_schema.cpp does not list it";
  }
}

TEST(ConfigSchema, EveryKeyInTheTableIsAccepted) {
  const auto keys = recorded({kDefaults, kBranches, kFullCar, kDatasheet, measuredSurface()});
  for (const ConfigKey& k : configSchema()) {
    if (kReadBeforeTheReader.count(k.path)) continue;
    const auto it = keys.find(k.path);
    // A map of keys may be documented as a whole (`tolerances`).
    EXPECT_TRUE(it != keys.end() && (isKey(it->second) || std::string(k.type) == "map"))
        << "src/io/config_schema.cpp lists '" << k.path << "' but the parser never reads it";
  }
  // The one read before: a config naming a vehicle file loads.
  const std::string file = ::testing::TempDir() + "/schema_vehicle.yaml";
  std::ofstream(file) << "vehicle: {bar_mass: 590.0}\n";
  const EstimatorConfig c =
      parseConfigString(std::string(kDefaults) + "vehicle_file: " + file + "\n", "vf.yaml");
  EXPECT_EQ(c.vehicle_file, file);
}

TEST(ConfigSchema, TypesAreWhatTheParserReads) {
  // A read's kind and the table types it may be documented as.
  const std::map<std::string, std::set<std::string>> accepted = {
      {"number", {"number"}},       {"integer", {"integer"}},
      {"unsigned", {"unsigned"}},   {"text", {"text", "bool", "choice"}},
      {"number list", {"numbers"}}, {"text list", {"names"}},
      {"number or list", {"number", "numbers"}},
      {"map", {"map"}},             {"list", {"list"}}};
  const auto table = tableByPath();
  for (const auto& [path, rec] : recorded({kDefaults, kBranches, kFullCar, kDatasheet, measuredSurface()})) {
    if (!isKey(rec) || !table.count(path)) continue;
    std::set<std::string> words;  // "number or numbers" -> {number, numbers}
    const std::string type = table.at(path)->type;
    for (std::size_t at = 0; at <= type.size();) {
      const std::size_t end = std::min(type.find(" or ", at), type.size());
      words.insert(type.substr(at, end - at));
      at = end + 4;
    }
    for (const std::string& kind : rec.kinds) {
      if (kind == "map" && rec.has_children) continue;  // a map of keys, documented as a value
      bool ok = false;
      for (const std::string& t : accepted.at(kind)) ok |= words.count(t) > 0;
      EXPECT_TRUE(ok) << path << ": the parser reads a " << kind << ", the table says " << type;
    }
  }
}

// The default (or range) the table gives is the one the parser holds when
// the key is absent; defaults that name where they come from ("the vehicle
// value", "required", ...) are not literal and not compared.
TEST(ConfigSchema, DefaultsAndRangesAreTheParsers) {
  const auto table = tableByPath();
  std::set<std::string> compared;
  for (const YamlKeyRead& r : readsOf(kDefaults)) {
    const std::string path = tablePath(r.path);
    if (!table.count(path) || path.find('<') != std::string::npos) continue;
    const ConfigKey& k = *table.at(path);
    const std::string d = k.default_value;
    if (startsWith(d, "required") || startsWith(d, "the ") || startsWith(d, "none") ||
        startsWith(d, "unset")) {
      continue;
    }
    compared.insert(path);
    EXPECT_TRUE(sameUpToNote(d, r.value))
        << path << ": the table's default is '" << d << "', the parser's '" << r.value << "'";
    if (!r.domain.empty()) {
      EXPECT_TRUE(sameUpToNote(k.domain, r.domain))
          << path << ": the table's domain is '" << k.domain << "', the parser's '" << r.domain
          << "'";
    }
  }
  EXPECT_GT(compared.size(), 90u);  // the comparison reached the keys
}

// A default the table gets wrong is caught: the check above is not vacuous.
TEST(ConfigSchema, AWrongDefaultWouldNotMatch) {
  for (const YamlKeyRead& r : readsOf(kDefaults)) {
    if (r.path == "pc.order") {
      EXPECT_FALSE(sameUpToNote("5", r.value));
    }
    if (r.path == "truth.xi") {
      EXPECT_FALSE(sameUpToNote("[0.2326, -0.3875]", r.value));
    }
  }
}

std::string fileText(const std::string& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in) << path << " missing";
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// configuration.md: each `<!-- config_schema: a b -->` ... `<!-- end config_schema -->`
// block holds configSchemaMarkdown({a, b}); every section is in one block.
TEST(ConfigSchema, ConfigurationMdCarriesTheGeneratedTables) {
  const std::string path = std::string(PC_EKF_SOURCE_DIR) + "/docs/configuration.md";
  const std::string text = fileText(path);
  const std::string open = "<!-- config_schema:", close = "<!-- end config_schema -->";
  std::string updated;
  std::set<std::string> covered;
  std::size_t at = 0;
  while (true) {
    const std::size_t begin = text.find(open, at);
    if (begin == std::string::npos) break;
    const std::size_t line_end = text.find("-->\n", begin);
    const std::size_t end = text.find(close, begin);
    ASSERT_TRUE(line_end != std::string::npos && end != std::string::npos && line_end < end);
    std::istringstream names(text.substr(begin + open.size(), line_end - begin - open.size()));
    std::vector<std::string> sections;
    for (std::string s; names >> s;) {
      sections.push_back(s);
      EXPECT_TRUE(covered.insert(s).second) << "section " << s << " in two blocks";
    }
    const std::size_t body = line_end + 4;
    const std::string expected = configSchemaMarkdown(sections);
    EXPECT_EQ(text.substr(body, end - body), expected)
        << "docs/configuration.md is out of date; regenerate with PC_EKF_UPDATE_DOCS=1 "
           "test_io_config_schema";
    updated += text.substr(at, body - at) + expected;
    at = end;
  }
  updated += text.substr(at);
  for (const ConfigKey& k : configSchema()) {
    EXPECT_TRUE(covered.count(configSection(k.path)))
        << "no config_schema block in docs/configuration.md shows section "
        << configSection(k.path);
  }
  if (std::getenv("PC_EKF_UPDATE_DOCS") && updated != text) {
    std::ofstream(path) << updated;
    std::cout << "rewrote " << path << "\n";
  }
}

// config/speed_bump.yaml lists every key, set or in a comment: each key's
// last name appears as `name:` inside its section (the block from the
// section's line at column 0, `# section:` when commented, to the next).
TEST(ConfigSchema, SpeedBumpYamlListsEveryKey) {
  std::ifstream in(std::string(PC_EKF_SOURCE_DIR) + "/config/speed_bump.yaml");
  ASSERT_TRUE(in);
  std::map<std::string, std::string> sections;  // section -> its lines
  std::string current;
  const std::regex top("^#? ?([a-z_]+):( |$).*");
  for (std::string line; std::getline(in, line);) {
    std::smatch m;
    if (std::regex_match(line, m, top)) current = m[1];
    if (!current.empty()) sections[current] += line + "\n";
  }
  for (const ConfigKey& k : configSchema()) {
    const std::string path = k.path;
    const std::string section = configSection(path);
    ASSERT_TRUE(sections.count(section)) << "config/speed_bump.yaml has no " << section << ":";
    const std::size_t last = path.find_last_of(".]");
    const std::string name = last == std::string::npos ? path : path.substr(last + 1);
    if (name.empty() || name[0] == '<') continue;  // a model's names: its own tables
    EXPECT_TRUE(std::regex_search(sections[section], std::regex("(^|[\\s{,#])" + name + ":")))
        << "config/speed_bump.yaml does not list " << path;
  }
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
