// Fuzz target: bag reading (pc_ekf::readBag, src/ros/bag_io.h) -- the path of
// `estimate_offline --bag` and of replay_node's bag loading -- on the fuzz
// bytes written to a temporary file.
// Contract (bag_io.h): a missing, unreadable, truncated or corrupt bag throws
// pc_ekf::BagError; a bag that reads satisfies the BagRecord invariants
// (road and sample times finite, >= 0, strictly increasing; values finite;
// channels ascending; at least one sample). Anything else (another exception,
// crash, sanitizer report in our code, hang, huge allocation) is a bug.
// rosbag itself is the system library (not instrumented): inside it only
// crashes, hangs and allocations are seen, not silent out-of-bounds reads.
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "pc_ekf/ros/bag_io.h"

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

void checkRecord(const pc_ekf::BagRecord& r) {
  const pc_ekf::ContactSeries& road = r.road_contacts;
  check(!road.t.empty() && road.heights.size() == 2 && road.heights[0].size() == road.t.size() &&
        road.heights[1].size() == road.t.size());
  check(road.t.front() == 0.0);
  for (std::size_t i = 0; i < road.t.size(); ++i) {
    check(std::isfinite(road.t[i]) && std::isfinite(road.heights[0][i]) &&
          std::isfinite(road.heights[1][i]));
    if (i > 0) check(road.t[i] > road.t[i - 1]);
  }
  check(!r.samples.empty());
  for (std::size_t i = 0; i < r.samples.size(); ++i) {
    const pc_ekf::Measurement& m = r.samples[i];
    check(std::isfinite(m.time) && m.time >= 0.0);
    if (i > 0) check(m.time > r.samples[i - 1].time);
    check(static_cast<Eigen::Index>(m.channels.size()) == m.values.size() && !m.channels.empty());
    for (std::size_t k = 0; k < m.channels.size(); ++k) {
      check(m.channels[k] >= 0 && m.channels[k] < 7);  // the roll plane: u, v and IMU
      if (k > 0) check(m.channels[k] > m.channels[k - 1]);
    }
    check(m.values.allFinite());
  }
}

std::string temporaryBag() {
  const char* dir = std::getenv("TMPDIR");
  std::string pattern = std::string(dir && *dir ? dir : "/tmp") + "/pc_ekf_fuzz_XXXXXX.bag";
  const int fd = mkstemps(pattern.data(), 4);
  if (fd < 0) std::abort();
  close(fd);
  return pattern;
}

const std::string& bagPath() {
  static const std::string path = temporaryBag();
  static const bool cleanup = [] { return std::atexit([] { std::remove(bagPath().c_str()); }) == 0; }();
  (void)cleanup;
  return path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string& path = bagPath();
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();
  if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
  static const bool verbose = std::getenv("PC_EKF_FUZZ_VERBOSE") != nullptr;  // outcome to stderr
  try {
    const pc_ekf::BagRecord record = pc_ekf::readBag(path);
    checkRecord(record);
    if (verbose) {
      std::fprintf(stderr, "read: %zu road samples, %zu samples\n", record.road_contacts.t.size(),
                   record.samples.size());
    }
  } catch (const pc_ekf::BagError& e) {
    if (verbose) std::fprintf(stderr, "BagError: %s\n", e.what());
  }
  return 0;
}
