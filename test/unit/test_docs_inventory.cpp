// The docs' inventories are complete: every executable and script the
// package installs (CMakeLists.txt) is in docs/tools.md, every rostest
// (test/ros/*.test) in docs/reliability.md's rostest table. The docs say
// what the code does: their history (commit hashes, times of day, dates,
// work-log and before/after wording) lives in CHANGELOG.md only, studies
// (docs/studies/) excepted. The user path stays short, and every relative
// link in README.md and docs/ leads to a file that exists.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace {

const std::string kRoot = PC_EKF_SOURCE_DIR;

std::string fileText(const std::string& path) {
  std::ifstream in(kRoot + "/" + path);
  EXPECT_TRUE(in) << path << " missing";
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// Words of the first CMake call matching `call` (e.g. "set\\(PC_EKF_TOOLS").
std::vector<std::string> cmakeWords(const std::string& cmake, const std::string& call) {
  std::smatch m;
  EXPECT_TRUE(std::regex_search(cmake, m, std::regex(call + "([^)]*)\\)"))) << call;
  std::istringstream in(m[1].str());
  std::vector<std::string> out;
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

// What the package installs as a program: the tools, the nodes, the soak
// executable, the Python scripts and the scripts of launch_free_scripts/.
std::set<std::string> installedPrograms() {
  const std::string cmake = fileText("CMakeLists.txt");
  std::set<std::string> out;
  for (const auto& w : cmakeWords(cmake, "set\\(PC_EKF_TOOLS")) out.insert(w);
  // foreach(name a b) pc_ekf_executable(${name} ...): the nodes.
  const std::regex nodes("foreach\\(name ([a-z_ ]+)\\)\\s*pc_ekf_executable");
  for (auto it = std::sregex_iterator(cmake.begin(), cmake.end(), nodes);
       it != std::sregex_iterator(); ++it) {
    std::istringstream in((*it)[1].str());
    for (std::string w; in >> w;) out.insert(w);
  }
  for (const auto& w : cmakeWords(cmake, "catkin_install_python\\(PROGRAMS")) {
    if (w.rfind("scripts/", 0) == 0) out.insert(w.substr(8));
  }
  EXPECT_NE(cmake.find("install(TARGETS soak_estimator"), std::string::npos);
  out.insert("soak_estimator");
  EXPECT_NE(cmake.find("install(DIRECTORY launch_free_scripts"), std::string::npos);
  for (const auto& e : std::filesystem::directory_iterator(kRoot + "/launch_free_scripts")) {
    if (e.path().extension() == ".sh") out.insert(e.path().filename().string());
  }
  return out;
}

TEST(DocsInventory, EveryInstalledProgramIsInToolsMd) {
  const std::string tools = fileText("docs/tools.md");
  const std::set<std::string> programs = installedPrograms();
  EXPECT_GE(programs.size(), 20u);  // the parse found them
  for (const std::string& name : programs) {
    EXPECT_NE(tools.find("`" + name + "`"), std::string::npos)
        << name << " is installed but docs/tools.md does not list it";
  }
}

TEST(DocsInventory, EveryRostestIsInReliabilityMd) {
  const std::string reliability = fileText("docs/reliability.md");
  int count = 0;
  for (const auto& e : std::filesystem::directory_iterator(kRoot + "/test/ros")) {
    if (e.path().extension() != ".test") continue;
    ++count;
    const std::string name = e.path().stem().string();
    EXPECT_NE(reliability.find("| `" + name + "` |"), std::string::npos)
        << "rostest " << name << " is not in docs/reliability.md's rostest table";
  }
  EXPECT_GT(count, 10);
}

// 7-40 hex digits with a letter and a digit.
const std::regex& commitHash() {
  static const std::regex hash("\\b(?=[0-9a-f]*[a-f])(?=[0-9a-f]*[0-9])[0-9a-f]{7,40}\\b");
  return hash;
}

// README.md and every docs/**/*.md outside docs/studies/ (the measurement
// reports, which record what was tried).
std::vector<std::string> referenceDocs() {
  std::vector<std::string> files = {"README.md"};
  for (const auto& e : std::filesystem::recursive_directory_iterator(kRoot + "/docs")) {
    if (e.path().extension() != ".md") continue;
    const std::string rel = std::filesystem::relative(e.path(), kRoot).generic_string();
    if (rel.rfind("docs/studies/", 0) == 0) continue;
    files.push_back(rel);
  }
  std::sort(files.begin(), files.end());
  return files;
}

// Before/after and dated wording: what a config or the code did once.
const std::regex& beforeAfter() {
  static const std::regex r(
      "used to be|as the file had it|had it before|earlier setting|no longer uses|\\btoday\\b|"
      "the file had then|as shipped now|"
      "\\bbefore:|\\bnow\\b[^.]*\\binstead of\\b|\\b20[0-9]{2}-[01][0-9]-[0-3][0-9]\\b",
      std::regex::icase);
  return r;
}

// No commit hash (7-40 hex digits with a letter and a digit), no time of
// day (hh:mm), no date, no work-log or before/after phrase.
TEST(DocsInventory, HistoryIsOnlyInTheChangelog) {
  const std::vector<std::string> files = referenceDocs();
  EXPECT_GT(files.size(), 10u);
  const std::regex& hash = commitHash();
  const std::regex clock("\\b([01][0-9]|2[0-3]):[0-5][0-9]\\b");
  const std::regex log("this session|previous session|earlier session|before that|"
                       "what changed|yesterday|this morning|this afternoon",
                       std::regex::icase);
  for (const std::string& file : files) {
    std::istringstream text(fileText(file));
    int line_number = 0;
    for (std::string line; std::getline(text, line);) {
      ++line_number;
      std::smatch m;
      for (const std::regex* r : {&hash, &clock, &log, &beforeAfter()}) {
        if (std::regex_search(line, m, *r)) {
          ADD_FAILURE() << file << ":" << line_number << ": '" << m[0]
                        << "' is history; it belongs in CHANGELOG.md";
        }
      }
    }
  }
}

// The user path (getting started, configure, read the estimate) stays a
// short read.
TEST(DocsInventory, UserPathIsShort) {
  int lines = 0;
  for (const char* file :
       {"docs/getting_started.md", "docs/configure.md", "docs/read_the_estimate.md"}) {
    const std::string text = fileText(file);
    lines += static_cast<int>(std::count(text.begin(), text.end(), '\n'));
  }
  EXPECT_GT(lines, 100);
  EXPECT_LE(lines, 1200) << "the user path has " << lines << " lines";
}

// Relative link targets of a markdown text, outside code blocks and code spans.
std::vector<std::string> relativeLinks(const std::string& markdown) {
  std::vector<std::string> out;
  std::istringstream text(markdown);
  bool fenced = false;
  const std::regex span("`[^`]*`");
  const std::regex link("\\]\\(([^)\\s]+)\\)");
  const std::regex absolute("^[a-zA-Z][a-zA-Z0-9+.-]*:");
  for (std::string line; std::getline(text, line);) {
    if (line.rfind("```", 0) == 0) {
      fenced = !fenced;
      continue;
    }
    if (fenced) continue;
    const std::string prose = std::regex_replace(line, span, "");
    for (auto it = std::sregex_iterator(prose.begin(), prose.end(), link);
         it != std::sregex_iterator(); ++it) {
      const std::string target = (*it)[1].str();
      if (target.empty() || target[0] == '#' || std::regex_search(target, absolute)) continue;
      out.push_back(target.substr(0, target.find('#')));
    }
  }
  return out;
}

TEST(DocsInventory, EveryRelativeLinkLeadsToAFile) {
  std::vector<std::string> files = {"README.md"};
  for (const auto& e : std::filesystem::recursive_directory_iterator(kRoot + "/docs")) {
    if (e.path().extension() == ".md") {
      files.push_back(std::filesystem::relative(e.path(), kRoot).generic_string());
    }
  }
  int links = 0;
  for (const std::string& file : files) {
    const std::filesystem::path dir = std::filesystem::path(kRoot) / file;
    for (const std::string& target : relativeLinks(fileText(file))) {
      ++links;
      EXPECT_TRUE(std::filesystem::exists(dir.parent_path() / target))
          << file << " links to " << target << ", which does not exist";
    }
  }
  EXPECT_GT(links, 50);
}

// The check above finds what it looks for.
TEST(DocsInventory, HistoryPatternsMatch) {
  const std::regex& hash = commitHash();
  EXPECT_TRUE(std::regex_search(std::string("a clean checkout of b05076a"), hash));
  EXPECT_FALSE(std::regex_search(std::string("1000000 samples, defaced"), hash));
  EXPECT_TRUE(std::regex_search(std::string("shrink 0.01, as the file had it"), beforeAfter()));
  EXPECT_TRUE(std::regex_search(std::string("measured on 2026-12-05"), beforeAfter()));
  EXPECT_FALSE(std::regex_search(std::string("124 points instead of 306"), beforeAfter()));
  const std::vector<std::string> links =
      relativeLinks("[a](b.md#c) `[x](y.md)` [w](https://e.org) [s](#t)\n```\n[u](v.md)\n```\n");
  EXPECT_EQ(links, std::vector<std::string>{"b.md"});
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
