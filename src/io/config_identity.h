// The identity of a configuration: its parsed YAML as canonical text and a
// stable hash of that text. Checkpoints store the hash so that a resumed run
// can refuse a state computed under another configuration.
#pragma once

#include <cstdint>
#include <string>

namespace YAML {
class Node;
}

namespace pc_ekf {

// 64-bit FNV-1a: stable across runs, compilers and machines.
std::uint64_t fnv1a64(const std::string& text);

// The configuration as one "key.path = value" line per leaf, keys sorted:
// the same text for the same parsed YAML whatever the comments, spacing and
// key order of the file. Hash it with fnv1a64 for Checkpoint::config_hash.
std::string canonicalConfigText(const YAML::Node& config);

std::string hashText(std::uint64_t hash);  // 0x + 16 hex digits

}  // namespace pc_ekf
