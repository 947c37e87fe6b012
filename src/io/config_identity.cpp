#include "pc_ekf/io/config_identity.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdio>
#include <vector>

namespace pc_ekf {
namespace {

void flatten(const YAML::Node& n, const std::string& path, std::vector<std::string>& lines) {
  const std::string at = path.empty() ? "(root)" : path;
  switch (n.Type()) {
    case YAML::NodeType::Map:
      if (n.size() == 0) lines.push_back(at + " = {}");
      for (const auto& kv : n) {
        const std::string key = kv.first.as<std::string>();
        flatten(kv.second, path.empty() ? key : path + "." + key, lines);
      }
      break;
    case YAML::NodeType::Sequence:
      if (n.size() == 0) lines.push_back(at + " = []");
      for (std::size_t i = 0; i < n.size(); ++i) {
        flatten(n[i], path + "[" + std::to_string(i) + "]", lines);
      }
      break;
    case YAML::NodeType::Scalar:
      lines.push_back(at + " = " + n.Scalar());
      break;
    default:
      lines.push_back(at + " = ~");
  }
}

}  // namespace

std::uint64_t fnv1a64(const std::string& text) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char c : text) {
    h ^= c;
    h *= 0x100000001b3ull;
  }
  return h;
}

std::string hashText(std::uint64_t hash) {
  char text[24];
  std::snprintf(text, sizeof(text), "0x%016llx", static_cast<unsigned long long>(hash));
  return text;
}

std::string canonicalConfigText(const YAML::Node& config) {
  std::vector<std::string> lines;
  flatten(config, "", lines);
  std::sort(lines.begin(), lines.end());
  std::string out;
  for (const auto& l : lines) out += l + "\n";
  return out;
}

}  // namespace pc_ekf
