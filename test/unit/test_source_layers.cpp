// The source folders are layers, pc <- model <- filter <- io <- ros <- tools:
// a file includes its own folder's headers and those of the layers below,
// never one above (README, Layout). Inside io/ the files
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

const std::vector<std::string> kLayers{"pc", "model", "filter", "io", "ros", "tools"};

int layerOf(const std::string& folder) {
  for (std::size_t i = 0; i < kLayers.size(); ++i) {
    if (kLayers[i] == folder) return static_cast<int>(i);
  }
  return -1;
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
  for (const std::string& folder : kLayers) {
    for (const fs::path& f : sources(folder)) {
      ++files;
      for (const auto& [to, name] : packageIncludes(f)) {
        if (layerOf(to) < 0) continue;  // messages and other generated headers
        EXPECT_LE(layerOf(to), layerOf(folder))
            << "src/" << folder << "/" << f.filename().string() << " includes pc_ekf/" << to << "/"
            << name << ".h, a layer above";
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
