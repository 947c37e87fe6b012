// The source folders are layers,
//   pc <- model <- filter <- {reference, health, sensitivity} <- io <- ros <- tools:
// a file includes its own folder's headers and those of the layers below,
// never one above nor a sibling (reference/, health/ and sensitivity/ each
// build on filter/, not on each other; README, Layout). Inside io/ the files
// are layered too: taking a header and its .cpp as one unit, no chain of
// includes leads back to where it started.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

// Each folder and the folders it may include (besides its own): those below it.
const std::map<std::string, std::set<std::string>>& kBelow() {
  static const std::map<std::string, std::set<std::string>> below = [] {
    std::map<std::string, std::set<std::string>> b;
    b["pc"] = {};
    b["model"] = {"pc"};
    b["filter"] = {"pc", "model"};
    for (const char* sibling : {"reference", "health", "sensitivity"}) {
      b[sibling] = {"pc", "model", "filter"};
    }
    b["io"] = {"pc", "model", "filter", "reference", "health", "sensitivity"};
    b["ros"] = b["io"];
    b["ros"].insert("io");
    b["tools"] = b["ros"];
    b["tools"].insert("ros");
    return b;
  }();
  return below;
}

bool isLayer(const std::string& folder) { return kBelow().count(folder) > 0; }

TEST(SourceLayers, EveryFolderIsALayer) {
  for (const auto& e : fs::directory_iterator(fs::path(PC_EKF_SOURCE_DIR) / "src")) {
    if (e.is_directory()) {
      EXPECT_TRUE(isLayer(e.path().filename().string()))
          << "src/" << e.path().filename().string() << " has no place in the layers";
    }
  }
}

// Each `#include "pc_ekf/<folder>/<name>.h"` (or <...>) of a file: folder, name.
std::vector<std::pair<std::string, std::string>> packageIncludes(const fs::path& file) {
  static const std::regex include(R"(^\s*#\s*include\s*["<]pc_ekf/(\w+)/(\w+)\.h[">])");
  std::vector<std::pair<std::string, std::string>> out;
  std::ifstream in(file);
  for (std::string line; std::getline(in, line);) {
    std::smatch m;
    if (std::regex_search(line, m, include)) out.emplace_back(m[1].str(), m[2].str());
  }
  return out;
}

std::vector<fs::path> sources(const std::string& folder) {
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(fs::path(PC_EKF_SOURCE_DIR) / "src" / folder)) {
    const std::string ext = e.path().extension().string();
    if (ext == ".h" || ext == ".cpp") out.push_back(e.path());
  }
  return out;
}

TEST(SourceLayers, NoIncludeRunsUpTheLayers) {
  int files = 0;
  for (const auto& [folder, below] : kBelow()) {
    for (const fs::path& f : sources(folder)) {
      ++files;
      for (const auto& [to, name] : packageIncludes(f)) {
        if (!isLayer(to)) continue;  // messages and other generated headers
        EXPECT_TRUE(to == folder || below.count(to) > 0)
            << "src/" << folder << "/" << f.filename().string() << " includes pc_ekf/" << to << "/"
            << name << ".h, a layer above or beside";
      }
    }
  }
  EXPECT_GT(files, 100);
}

// Depth-first search for a chain back to a unit on the current path.
bool cycleFrom(const std::string& u, const std::map<std::string, std::set<std::string>>& graph,
               std::map<std::string, int>& state, std::vector<std::string>& path) {
  state[u] = 1;
  path.push_back(u);
  const auto it = graph.find(u);
  if (it != graph.end()) {
    for (const std::string& v : it->second) {
      if (state[v] == 1) {
        path.push_back(v);
        return true;
      }
      if (state[v] == 0 && cycleFrom(v, graph, state, path)) return true;
    }
  }
  state[u] = 2;
  path.pop_back();
  return false;
}

TEST(SourceLayers, IoFilesIncludeEachOtherWithoutACycle) {
  std::map<std::string, std::set<std::string>> graph;
  for (const fs::path& f : sources("io")) {
    const std::string unit = f.stem().string();
    for (const auto& [to, name] : packageIncludes(f)) {
      if (to == "io" && name != unit) graph[unit].insert(name);
    }
  }
  EXPECT_GT(graph.size(), 5u);
  std::map<std::string, int> state;
  for (const auto& [unit, _] : graph) {
    std::vector<std::string> path;
    if (state[unit] == 0 && cycleFrom(unit, graph, state, path)) {
      std::string chain;
      for (const std::string& p : path) chain += (chain.empty() ? "" : " -> ") + p;
      ADD_FAILURE() << "io/ includes run in a circle: " << chain;
      break;
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
