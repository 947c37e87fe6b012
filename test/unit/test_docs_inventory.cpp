// The docs' inventories are complete: every executable and script the
// package installs (CMakeLists.txt) is in docs/tools.md, every rostest
// (test/ros/*.test) in docs/reliability.md's rostest table. And the docs
// say what the code does: their history (commit hashes, times of day,
// work-log wording) lives in CHANGELOG.md only.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>

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

// README.md and docs/*.md: no commit hash (7-40 hex digits with a letter
// and a digit), no time of day (hh:mm) and no work-log phrase.
TEST(DocsInventory, HistoryIsOnlyInTheChangelog) {
  std::vector<std::string> files = {"README.md"};
  for (const auto& e : std::filesystem::directory_iterator(kRoot + "/docs")) {
    if (e.path().extension() == ".md") files.push_back("docs/" + e.path().filename().string());
  }
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
      for (const std::regex* r : {&hash, &clock, &log}) {
        if (std::regex_search(line, m, *r)) {
          ADD_FAILURE() << file << ":" << line_number << ": '" << m[0]
                        << "' is history; it belongs in CHANGELOG.md";
        }
      }
    }
  }
}

// The check above finds what it looks for.
TEST(DocsInventory, HistoryPatternsMatch) {
  const std::regex& hash = commitHash();
  EXPECT_TRUE(std::regex_search(std::string("a clean checkout of b05076a"), hash));
  EXPECT_FALSE(std::regex_search(std::string("1000000 samples, defaced"), hash));
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
