// estimator_node checkpoints (io/checkpoint.h): the state reads back
// bit-exactly, a damaged or foreign file is refused naming the file and the
// key, the config hash ignores layout but not values.
#include <gtest/gtest.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "pc_ekf/io/checkpoint.h"

namespace pc_ekf {
namespace {

std::string tempPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() /
          ("pc_ekf_checkpoint_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

std::string readText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void writeText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Doubles that a careless format loses: thirds, tiny, huge, negative zero.
Checkpoint sampleCheckpoint() {
  Checkpoint c;
  c.config_hash = 0x8000000000000001ull;  // top bit set: no signed overflow
  c.road_mode = "topic";
  c.origin = {999, 970000000};
  c.last_sample = {1001, 50000000};
  c.full.x.resize(3, 4);
  for (Eigen::Index i = 0; i < c.full.x.size(); ++i) {
    c.full.x(i) = std::pow(-1.0, static_cast<double>(i)) / 3.0 * std::pow(10.0, i * 7 - 30);
  }
  c.full.x(0, 3) = -0.0;
  c.full.x(1, 3) = std::numeric_limits<double>::denorm_min();
  c.full.x(2, 3) = std::numeric_limits<double>::max();
  c.full.time = 1.08;
  c.full.samples = 36;
  c.decimated.x = c.full.x * 0.1;
  c.full.working = c.full.x.bottomRows(2) / 7.0;  // a working prior; decimated: none
  c.decimated.time = 0.9;
  c.decimated.samples = 3;
  c.coherence_disagreement = Eigen::Vector2d(0.1, 2.0 / 3.0);
  Measurement a;
  a.time = 0.03;
  a.channels = {0, 1, 2, 3};
  a.values = Eigen::Vector4d(1e-3, -2e-3, 0.1 / 3.0, 7.0);
  Measurement b;
  b.time = 0.06;
  b.channels = {2};
  b.values = Eigen::VectorXd::Constant(1, -1.0 / 7.0);
  c.batch_samples = {a, b};
  c.batch_last_stamp = {1000, 60000000};
  c.road.t = {0.9, 0.9 + 1.0 / 3.0, 1.3};
  c.road.heights = {{0.0, 1e-300, -0.1 / 3.0}, {0.05, -0.0, 2.0 / 7.0}};
  c.road_last_stamp = {1001, 270000000};
  c.counters = {{"samples_received", 40}, {"samples_rejected.duplicate_stamp", 2}};
  return c;
}

std::string errorOf(const std::string& path) {
  try {
    readCheckpoint(path);
  } catch (const CheckpointError& e) {
    return e.what();
  }
  return "";
}

TEST(Checkpoint, RoundTripIsBitExact) {
  const std::string path = tempPath("round_trip");
  const Checkpoint c = sampleCheckpoint();
  writeCheckpoint(c, path);
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  const Checkpoint r = readCheckpoint(path);
  EXPECT_EQ(r.config_hash, c.config_hash);
  EXPECT_EQ(r.road_mode, "topic");
  EXPECT_EQ(r.origin.sec, 999u);
  EXPECT_EQ(r.origin.nsec, 970000000u);
  EXPECT_EQ(r.last_sample.sec, 1001u);
  EXPECT_EQ(r.last_sample.nsec, 50000000u);
  ASSERT_EQ(r.full.x.rows(), 3);
  ASSERT_EQ(r.full.x.cols(), 4);
  for (Eigen::Index i = 0; i < c.full.x.size(); ++i) {
    EXPECT_TRUE(sameBits(r.full.x(i), c.full.x(i))) << i << ": " << r.full.x(i);
    EXPECT_TRUE(sameBits(r.decimated.x(i), c.decimated.x(i))) << i;
  }
  EXPECT_TRUE(std::signbit(r.full.x(0, 3)));
  EXPECT_TRUE(sameBits(r.full.time, 1.08));
  EXPECT_EQ(r.full.samples, 36);
  EXPECT_EQ(r.decimated.samples, 3);
  ASSERT_EQ(r.full.working.rows(), 2);
  ASSERT_EQ(r.full.working.cols(), 4);
  for (Eigen::Index i = 0; i < c.full.working.size(); ++i) {
    EXPECT_TRUE(sameBits(r.full.working(i), c.full.working(i))) << i;
  }
  EXPECT_EQ(r.decimated.working.size(), 0);
  ASSERT_TRUE(r.coherence_disagreement.has_value());
  EXPECT_TRUE(sameBits((*r.coherence_disagreement)(1), 2.0 / 3.0));
  ASSERT_EQ(r.batch_samples.size(), 2u);
  EXPECT_EQ(r.batch_samples[0].channels, (std::vector<int>{0, 1, 2, 3}));
  EXPECT_TRUE(sameBits(r.batch_samples[0].values(2), 0.1 / 3.0));
  EXPECT_EQ(r.batch_samples[1].channels, std::vector<int>{2});
  EXPECT_TRUE(sameBits(r.batch_samples[1].values(0), -1.0 / 7.0));
  EXPECT_TRUE(sameBits(r.batch_samples[1].time, 0.06));
  EXPECT_EQ(r.batch_last_stamp.nsec, 60000000u);
  ASSERT_EQ(r.road.t.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_TRUE(sameBits(r.road.t[i], c.road.t[i])) << i;
    EXPECT_TRUE(sameBits(r.road.heights[0][i], c.road.heights[0][i])) << i;
    EXPECT_TRUE(sameBits(r.road.heights[1][i], c.road.heights[1][i])) << i;
  }
  EXPECT_EQ(r.road_last_stamp.sec, 1001u);
  EXPECT_EQ(r.road_last_stamp.nsec, 270000000u);
  EXPECT_EQ(r.counters, c.counters);

  // Rewritten in place: the new state replaces the old one.
  Checkpoint next = c;
  next.full.samples = 43;
  next.coherence_disagreement.reset();
  next.batch_samples.clear();
  next.road_mode = "analytic";
  next.road = ContactSeries{};
  writeCheckpoint(next, path);
  const Checkpoint r2 = readCheckpoint(path);
  EXPECT_EQ(r2.full.samples, 43);
  EXPECT_FALSE(r2.coherence_disagreement.has_value());
  EXPECT_TRUE(r2.batch_samples.empty());
  EXPECT_TRUE(r2.road.t.empty());
  std::filesystem::remove(path);
}

TEST(Checkpoint, TruncatedFileIsRefused) {
  const std::string path = tempPath("truncated");
  writeCheckpoint(sampleCheckpoint(), path);
  const std::string text = readText(path);
  for (const std::size_t keep : {text.size() / 2, text.size() - 8, std::size_t{0}}) {
    writeText(path, text.substr(0, keep));
    const std::string e = errorOf(path);
    EXPECT_NE(e.find("checkpoint " + path), std::string::npos) << keep << ": " << e;
    EXPECT_NE(e.find("truncated"), std::string::npos) << keep << ": " << e;
  }
  // Cut inside the last line: "end = 36" -> "end = 3".
  writeText(path, text.substr(0, text.size() - 2));
  EXPECT_NE(errorOf(path).find("does not repeat full.samples"), std::string::npos) << errorOf(path);
  std::filesystem::remove(path);
  EXPECT_NE(errorOf(path).find("cannot open"), std::string::npos);
}

// Replaces the line starting with `key = ` (removes it when `line` is "").
std::string editLine(const std::string& text, const std::string& key, const std::string& line) {
  const std::size_t at = text.find("\n" + key + " = ");
  EXPECT_NE(at, std::string::npos) << key;
  const std::size_t end = text.find('\n', at + 1);
  return text.substr(0, at + 1) + line + (line.empty() ? "" : "\n") + text.substr(end + 1);
}

TEST(Checkpoint, DamagedValuesAreRefusedNamingTheKey) {
  const std::string path = tempPath("damaged");
  writeCheckpoint(sampleCheckpoint(), path);
  const std::string text = readText(path);
  const std::string x = text.substr(text.find("\nfull.x = ") + 1);
  const std::string x_line = x.substr(0, x.find('\n'));
  struct Case {
    std::string text, expected;
  };
  const std::vector<Case> cases{
      {editLine(text, "full.samples", ""), "key 'full.samples': missing"},
      {editLine(text, "full.x", "full.x = 3 5" + x_line.substr(std::strlen("full.x = 3 4"))),
       "key 'full.x': expected 17 values, got 14"},
      {editLine(text, "full.time", "full.time = nan"), "key 'full.time': 'nan' is not a finite"},
      {editLine(text, "full.time", "full.time = 1.08x"), "'1.08x' is not a finite number"},
      {editLine(text, "road_mode", "road_mode = bag"), "key 'road_mode': 'bag'"},
      {editLine(text, "road_mode", "road_mode = analytic"), "road samples with road_mode analytic"},
      {editLine(text, "road.2", "road.2 = 0.9 0 0"), "key 'road.2': time not after the previous"},
      {editLine(text, "road.1", "road.1 = 1 2"), "key 'road.1': expected 3 values, got 2"},
      {editLine(text, "format", "format = pc_ekf_checkpoint 1"), "expected 'pc_ekf_checkpoint 2'"},
      {editLine(text, "config_hash", "config_hash = 12"), "key 'config_hash'"},
      {editLine(text, "counter.samples_received", "colour.red = 1"), "key 'colour.red': unknown"},
      {editLine(text, "origin", "origin = 5 1000000000"), "key 'origin'"},
      {text + "origin = 1 2\n", "text after the 'end' line"},
  };
  for (const Case& c : cases) {
    writeText(path, c.text);
    const std::string e = errorOf(path);
    EXPECT_NE(e.find(c.expected), std::string::npos) << c.expected << " in: " << e;
    EXPECT_NE(e.find(path), std::string::npos) << e;
  }
  std::filesystem::remove(path);
}

TEST(Checkpoint, ForeignConfigHashIsRefusedNamingBothHashes) {
  const Checkpoint c = sampleCheckpoint();
  EXPECT_NO_THROW(requireConfigHash(c, c.config_hash, "a.ckpt"));
  try {
    requireConfigHash(c, 0x1234, "a.ckpt");
    FAIL() << "accepted a foreign hash";
  } catch (const CheckpointError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("checkpoint a.ckpt"), std::string::npos) << what;
    EXPECT_NE(what.find("0x8000000000000001"), std::string::npos) << what;
    EXPECT_NE(what.find("0x0000000000001234"), std::string::npos) << what;
    EXPECT_NE(what.find("configuration changed"), std::string::npos) << what;
  }
}

TEST(Checkpoint, ConfigHashIgnoresLayoutNotValues) {
  // FNV-1a 64 reference vectors.
  EXPECT_EQ(fnv1a64(""), 0xcbf29ce484222325ull);
  EXPECT_EQ(fnv1a64("a"), 0xaf63dc4c8601ec8cull);
  EXPECT_EQ(fnv1a64("foobar"), 0x85944171f73967e8ull);
  const auto hash = [](const std::string& yaml) {
    return fnv1a64(canonicalConfigText(YAML::Load(yaml)));
  };
  const std::uint64_t base = hash("pc: {order: 4}\nmeasurement:\n  r_relative: 0.01\n");
  EXPECT_EQ(base, hash("# comment\nmeasurement: {r_relative: 0.01}\npc:\n    order: 4\n"));
  EXPECT_NE(base, hash("pc: {order: 3}\nmeasurement:\n  r_relative: 0.01\n"));
  EXPECT_NE(base, hash("pc: {order: 4}\nmeasurement:\n  r_relative: 0.02\n"));
  EXPECT_NE(hash("a: [1, 2]"), hash("a: [2, 1]"));
  EXPECT_EQ(canonicalConfigText(YAML::Load("b: 1\na: {c: [x]}")), "a.c[0] = x\nb = 1\n");
}

TEST(Checkpoint, UnwritableDirectoryIsReportedAndLeavesNoTemporary) {
  const std::string path = "/nonexistent_pc_ekf_dir/run.ckpt";
  try {
    writeCheckpoint(sampleCheckpoint(), path);
    FAIL() << "wrote into a missing directory";
  } catch (const CheckpointError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  // A failed write leaves the previous checkpoint as it was.
  const std::string good = tempPath("kept");
  writeCheckpoint(sampleCheckpoint(), good);
  std::filesystem::create_directory(good + ".tmp");  // the temporary cannot be created
  EXPECT_THROW(writeCheckpoint(Checkpoint{}, good), CheckpointError);
  EXPECT_EQ(readCheckpoint(good).full.samples, 36);
  std::filesystem::remove(good + ".tmp");
  std::filesystem::remove(good);

  // A write that fails after the temporary was created and filled (the rename
  // over a directory fails) removes the temporary: the directory holds only
  // what was there before.
  const std::filesystem::path dir = tempPath("rename_fails");
  std::filesystem::create_directories(dir / "run.ckpt" / "occupied");
  const std::string blocked = (dir / "run.ckpt").string();
  try {
    writeCheckpoint(sampleCheckpoint(), blocked);
    FAIL() << "renamed a file over a non-empty directory";
  } catch (const CheckpointError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot rename " + blocked + ".tmp"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(blocked + ".tmp")) << "the temporary was left behind";
  std::vector<std::string> left;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    left.push_back(entry.path().filename().string());
  }
  EXPECT_EQ(left, std::vector<std::string>{"run.ckpt"});
  std::filesystem::remove_all(dir);
}

TEST(Checkpoint, RoadUnderFourContactsRoundTripsAndKeepsItsWidth) {
  Checkpoint c = sampleCheckpoint();
  c.road.heights = {{0.0, 0.1, 0.2}, {1.0 / 3.0, -0.0, 5e-324}, {0.0, 0.0, 0.08}, {1e300, 2.0, 3.0}};
  const std::string path = tempPath("four_contacts.ckpt");
  writeCheckpoint(c, path);
  const Checkpoint r = readCheckpoint(path);
  ASSERT_EQ(r.road.heights.size(), 4u);
  for (std::size_t k = 0; k < 4; ++k) {
    for (std::size_t i = 0; i < 3; ++i) EXPECT_TRUE(sameBits(r.road.heights[k][i], c.road.heights[k][i]));
  }
  // A row with a height missing is refused naming it.
  writeText(path, editLine(readText(path), "road.2", "road.2 = 1.3 0 0 0"));
  EXPECT_NE(errorOf(path).find("key 'road.2': expected 5 values, got 4"), std::string::npos)
      << errorOf(path);
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
