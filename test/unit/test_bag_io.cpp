// Bag layout of docs/method.md §8.2: synthesize_bag -> readBag round trip, topic
// matching, merging, and clear errors for unusable bags.
#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>

#include "bag_test_support.h"
#include "pc_ekf/ros/bag_io.h"
#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/io/measurement_csv.h"

namespace pc_ekf {
namespace {

using test::quote;
using test::ScratchDir;

Measurement sample(double t, std::vector<int> channels, std::vector<double> values) {
  Measurement m;
  m.time = t;
  m.channels = std::move(channels);
  m.values = Eigen::Map<const Eigen::VectorXd>(values.data(), values.size());
  return m;
}

// A small valid bag: road at 0, 0.1, ..., 1.0 s, three samples.
BagContents smallBag() {
  BagContents c;
  c.origin = ros::Time(500, 0);
  c.road_contacts.heights.resize(2);  // left, right (road/profile)
  for (int i = 0; i <= 10; ++i) {
    c.road_contacts.t.push_back(0.1 * i);
    c.road_contacts.heights[0].push_back(0.01 * i);
    c.road_contacts.heights[1].push_back(-0.02 * i);
  }
  c.samples = {sample(0.25, {0, 1, 2, 3}, {1, 2, 3, 4}), sample(0.5, {1, 2}, {5, 6}),
               sample(1.0, {3}, {7})};
  return c;
}

void expectMessageContains(const std::function<void()>& f, const std::string& a,
                           const std::string& b) {
  try {
    f();
    ADD_FAILURE() << "no BagError; expected one containing '" << b << "'";
  } catch (const BagError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(a, 0), 0u) << "message should start with the file name: " << what;
    EXPECT_NE(what.find(b), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << "one line: " << what;
  }
}

// ---------------------------------------------------------------- round trip

TEST(BagRoundTrip, SynthesizedBagGivesTheCsvSamplesAndTheAnalyticRoad) {
  ScratchDir dir;
  const std::string bag = dir.file("bump.bag"), csv = dir.file("bump.csv");
  const auto r = test::run(dir, PC_EKF_EXE_SYNTHESIZE_BAG,
                           "--config " + quote(test::config("speed_bump.yaml")) + " --output " +
                               quote(bag) + " --csv " + quote(csv) + " --seed 3");
  ASSERT_EQ(r.status, 0) << r.err;

  const BagRecord rec = readBag(bag);
  const MeasurementSeries expected = readMeasurementCsvFile(csv);
  EXPECT_EQ(rec.origin, ros::Time(1000000000, 0));
  EXPECT_EQ(rec.road_topic, "road/profile");
  EXPECT_EQ(rec.joint_states_topic, "suspension/joint_states");
  EXPECT_TRUE(rec.warnings.empty());
  ASSERT_EQ(rec.samples.size(), 10u);
  ASSERT_EQ(rec.samples.size(), expected.size());
  for (std::size_t k = 0; k < expected.size(); ++k) {
    EXPECT_NEAR(rec.samples[k].time, 0.3 * (k + 1), 1e-12);
    EXPECT_NEAR(rec.samples[k].time, expected[k].time, 1e-12);
    ASSERT_EQ(rec.samples[k].channels, expected[k].channels);
    EXPECT_LE((rec.samples[k].values - expected[k].values).cwiseAbs().maxCoeff(), 1e-12) << k;
  }
  // The same data as estimate_offline would synthesise with that seed.
  const EstimatorConfig config = loadConfigFile(test::config("speed_bump.yaml"));
  const auto road = std::dynamic_pointer_cast<const RoadInput>(makeRoad(config));
  const MeasurementSeries direct = synthesizeFromConfig(config, *makeModel(config, road), 3);
  EXPECT_LE((rec.samples.back().values - direct.back().values).cwiseAbs().maxCoeff(), 1e-12);

  // Road: 1 kHz from 0 to the last sample (3 s), the analytic bump's values.
  ASSERT_EQ(rec.road_contacts.t.size(), 3001u);
  double peak = 0.0;
  for (std::size_t i = 0; i < rec.road_contacts.t.size(); ++i) {
    ASSERT_NEAR(rec.road_contacts.t[i], i / 1000.0, 1e-12);
    const Eigen::Vector2d y = road->height(rec.road_contacts.t[i]);
    ASSERT_NEAR(rec.road_contacts.heights[0][i], y(0), 1e-12) << i;
    ASSERT_NEAR(rec.road_contacts.heights[1][i], y(1), 1e-12) << i;
    peak = std::max(peak, rec.road_contacts.heights[0][i]);
  }
  EXPECT_NEAR(peak, 0.10, 1e-12);

  ASSERT_TRUE(rec.ground_truth.has_value());
  EXPECT_EQ(rec.ground_truth->method, "truth");
  EXPECT_NEAR(rec.ground_truth->mean[0], 223.26, 1e-9);
  EXPECT_NEAR(rec.ground_truth->mean[1], 0.762 * (1 - 0.25 * 0.3875), 1e-12);
  EXPECT_EQ(rec.ground_truth->stddev, (std::vector<double>{0.0, 0.0}));
}

TEST(BagRoundTrip, TruthScheduleGivesAGroundTruthPerSample) {
  ScratchDir dir;
  const std::string yaml = dir.file("change.yaml"), bag = dir.file("change.bag");
  {
    std::ofstream out(yaml);
    out << test::readText(test::config("speed_bump.yaml"))
               .substr(0, test::readText(test::config("speed_bump.yaml")).find("truth:"))
        << "truth:\n  xi: [0.2326, -0.3875]\n  schedule: [{time: 1.5, values: {added_mass: "
           "263.26}}]\n";
  }
  const auto r = test::run(dir, PC_EKF_EXE_SYNTHESIZE_BAG,
                           "--config " + quote(yaml) + " --output " + quote(bag) + " --road-rate 100");
  ASSERT_EQ(r.status, 0) << r.err;
  rosbag::Bag in(bag, rosbag::bagmode::Read);
  std::vector<ParameterEstimate> truths;
  for (const auto& m : rosbag::View(in, rosbag::TopicQuery(std::string("ground_truth")))) {
    truths.push_back(*m.instantiate<ParameterEstimate>());
  }
  // One at t = 0, then one per sample at its stamp; the mass grows at 1.5 s.
  ASSERT_EQ(truths.size(), 11u);
  const ros::Time origin(1000000000, 0);
  EXPECT_EQ(truths[0].header.stamp, origin);
  EXPECT_EQ(truths[0].sample_index, 0u);
  EXPECT_NEAR(truths[0].mean[0], 223.26, 1e-9);
  for (std::size_t k = 1; k <= 10; ++k) {
    const double t = 0.3 * k;
    EXPECT_EQ(truths[k].sample_index, k);
    EXPECT_NEAR(truths[k].time, t, 1e-12);
    EXPECT_NEAR((truths[k].header.stamp - origin).toSec(), t, 1e-9);
    EXPECT_NEAR(truths[k].mean[0], k >= 5 ? 263.26 : 223.26, 1e-9) << k;
    EXPECT_NEAR(truths[k].xi_mean[0], k >= 5 ? 0.6326 : 0.2326, 1e-12) << k;
    EXPECT_NEAR(truths[k].mean[1], 0.762 * (1 - 0.25 * 0.3875), 1e-12);
    // The values only: the PC basis is in the first one.
    EXPECT_EQ(truths[k].names, truths[0].names);
    EXPECT_EQ(truths[k].method, "truth");
    EXPECT_TRUE(truths[k].coefficients.empty());
    EXPECT_EQ(truths[k].term_count, 0u);
  }
  EXPECT_EQ(truths[0].term_count, 15u);  // order 4, two germs
  EXPECT_EQ(truths[0].coefficients.size(), 30u);
  EXPECT_NEAR(readBag(bag).ground_truth->mean[0], 263.26, 1e-9);  // the last one
}

// A bag written before ParameterEstimate grew its safeguard and
// predictive-check fields (test/unit/data/speed_bump_n10_v0.bag, synthesize_bag
// of that time, config/speed_bump.yaml, road at 20 Hz): road and samples read
// as before, the ground truth (old definition) left out with a warning.
TEST(BagRoundTrip, BagWithAnOlderParameterEstimateStillReads) {
  const std::string bag = std::string(PC_EKF_SOURCE_DIR) + "/test/unit/data/speed_bump_n10_v0.bag";
  const BagRecord r = readBag(bag);
  EXPECT_EQ(r.samples.size(), 10u);
  EXPECT_EQ(r.road_contacts.t.size(), 61u);
  EXPECT_FALSE(r.ground_truth.has_value());
  bool warned = false;
  for (const auto& w : r.warnings) warned = warned || w.find("ground truth not read") != std::string::npos;
  EXPECT_TRUE(warned);
  // The same samples as the data the config synthesises today (same truth, seed, times).
  const EstimatorConfig c = loadConfigFile(std::string(PC_EKF_SOURCE_DIR) + "/config/speed_bump.yaml");
  const MeasurementSeries now = synthesizeFromConfig(c, *makeModel(c, makeRoad(c)), 1);
  ASSERT_EQ(now.size(), r.samples.size());
  for (std::size_t k = 0; k < now.size(); ++k) {
    EXPECT_NEAR(r.samples[k].time, now[k].time, 1e-9);
    EXPECT_EQ(r.samples[k].values, now[k].values) << k;
  }
}

TEST(BagRoundTrip, StartTimeAndRoadRateOptions) {
  ScratchDir dir;
  const std::string bag = dir.file("sine.bag");
  const auto r = test::run(dir, PC_EKF_EXE_SYNTHESIZE_BAG,
                           "--config " + quote(test::config("sine_1hz.yaml")) + " --output " +
                               quote(bag) + " --road-rate 200 --start-time 1234.5");
  ASSERT_EQ(r.status, 0) << r.err;
  const BagRecord rec = readBag(bag);
  EXPECT_EQ(rec.origin, ros::Time(1234, 500000000));
  ASSERT_EQ(rec.road_contacts.t.size(), 601u);
  EXPECT_NEAR(rec.road_contacts.t.back(), 3.0, 1e-12);
  // y1 = 0.05 sin(2 pi t), y2 = -y1 at t = 0.25 s (road sample 50).
  EXPECT_NEAR(rec.road_contacts.heights[0][50], 0.05, 1e-12);
  EXPECT_NEAR(rec.road_contacts.heights[1][50], -0.05, 1e-12);
  EXPECT_NEAR(rec.samples.front().time, 0.3, 1e-12);
}

TEST(BagRoundTrip, WrittenSubsetsNamespacesAndEqualStampsMerge) {
  ScratchDir dir;
  BagContents c = smallBag();
  c.road_topic = "/car1/road/profile";
  c.joint_states_topic = "/car1/suspension/joint_states";
  // Two messages with the same stamp and disjoint channels (e.g. two drivers).
  c.samples.push_back(sample(1.0, {0}, {8}));
  const std::string path = dir.file("ns.bag");
  writeBag(path, c);
  const BagRecord rec = readBag(path);
  EXPECT_EQ(rec.road_topic, "/car1/road/profile");
  EXPECT_EQ(rec.origin, ros::Time(500, 0));
  ASSERT_EQ(rec.samples.size(), 3u);
  EXPECT_EQ(rec.samples[1].channels, (std::vector<int>{1, 2}));
  EXPECT_EQ(rec.samples[1].values, Eigen::Vector2d(5, 6));
  EXPECT_EQ(rec.samples[2].time, 1.0);
  EXPECT_EQ(rec.samples[2].channels, (std::vector<int>{0, 3}));
  EXPECT_EQ(rec.samples[2].values, Eigen::Vector2d(8, 7));
  EXPECT_EQ(rec.road_contacts.heights[1][10], -0.2);
  EXPECT_FALSE(rec.ground_truth.has_value());
}

TEST(BagRoundTrip, ForeignJointsAreSkippedWithWarnings) {
  ScratchDir dir;
  const BagContents c = smallBag();
  const std::string path = dir.file("vehicle.bag");
  {
    rosbag::Bag bag(path, rosbag::bagmode::Write);
    for (std::size_t i = 0; i < c.road_contacts.t.size(); ++i) {
      const ros::Time s = stampAt(c.origin, c.road_contacts.t[i]);
      bag.write(
          "road/profile", s,
          roadProfileMessage(s, c.road_contacts.heights[0][i], c.road_contacts.heights[1][i]));
    }
    sensor_msgs::JointState js;
    js.header.stamp = stampAt(c.origin, 0.5);
    js.name = {"steering", "left_suspension"};
    js.position = {1.0, 0.02};
    bag.write("suspension/joint_states", js.header.stamp, js);
    js.header.stamp = stampAt(c.origin, 0.6);
    js.name = {"steering"};
    js.position = {1.0};
    bag.write("suspension/joint_states", js.header.stamp, js);
  }
  const BagRecord rec = readBag(path);
  ASSERT_EQ(rec.samples.size(), 1u);
  EXPECT_EQ(rec.samples[0].channels, (std::vector<int>{0}));
  EXPECT_EQ(rec.skipped_elements, 2);
  EXPECT_EQ(rec.empty_samples, 1);
  EXPECT_EQ(rec.warnings.size(), 3u);
}

TEST(BagTopics, SuffixMatching) {
  EXPECT_TRUE(topicMatches("road/profile", "road/profile"));
  EXPECT_TRUE(topicMatches("/road/profile", "road/profile"));
  EXPECT_TRUE(topicMatches("/car1/road/profile", "road/profile"));
  EXPECT_TRUE(topicMatches("/car1/road/profile", "/road/profile"));
  EXPECT_FALSE(topicMatches("/car1/offroad/profile", "road/profile"));
  EXPECT_FALSE(topicMatches("/road/profile/raw", "road/profile"));
  EXPECT_FALSE(topicMatches("profile", "road/profile"));
}

// ---------------------------------------------------------------- errors

TEST(BagErrors, MissingGarbageAndTruncatedFiles) {
  ScratchDir dir;
  const std::string missing = dir.file("missing.bag");
  expectMessageContains([&] { readBag(missing); }, missing, "no such bag file");

  const std::string garbage = dir.file("garbage.bag");
  std::ofstream(garbage) << "t,u1,u2,v1,v2\n0.3,1,2,3,4\n";
  expectMessageContains([&] { readBag(garbage); }, garbage, "bag");

  const std::string good = dir.file("good.bag");
  const auto r =
      test::run(dir, PC_EKF_EXE_SYNTHESIZE_BAG,
                "--config " + quote(test::config("speed_bump.yaml")) + " --output " + quote(good));
  ASSERT_EQ(r.status, 0) << r.err;
  ASSERT_NO_THROW(readBag(good));
  const auto size = std::filesystem::file_size(good);
  // Cut in the file header, in the middle of the data and just before the end.
  for (const double fraction : {0.001, 0.02, 0.5, 0.9, 0.999}) {
    const std::string cut = dir.file("cut.bag");
    std::filesystem::copy_file(good, cut, std::filesystem::copy_options::overwrite_existing);
    std::filesystem::resize_file(cut, static_cast<std::uintmax_t>(fraction * size));
    SCOPED_TRACE("truncated to " + std::to_string(fraction));
    expectMessageContains([&] { readBag(cut); }, cut, "bag");
  }
  // Overwritten bytes in the middle (a damaged chunk).
  const std::string damaged = dir.file("damaged.bag");
  std::filesystem::copy_file(good, damaged);
  {
    std::fstream f(damaged, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(size / 2));
    const std::string junk(4096, '\xff');
    f.write(junk.data(), static_cast<std::streamsize>(junk.size()));
  }
  try {
    const BagRecord rec = readBag(damaged);
    // Damage confined to message payload floats may still decode; then the
    // data must at least have the bag's shape.
    EXPECT_EQ(rec.samples.size(), 10u);
  } catch (const BagError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(damaged, 0), 0u) << e.what();
  }
}

TEST(BagErrors, NoRoadNoSamplesAndSamplesBeforeTheRoad) {
  ScratchDir dir;
  BagContents c = smallBag();
  c.road_contacts = ContactSeries{{}, {{}, {}}};  // no road messages
  const std::string no_road = dir.file("no_road.bag");
  writeBag(no_road, c);
  expectMessageContains([&] { readBag(no_road); }, no_road,
                        "no pc_ekf/RoadProfile messages on a topic ending in 'road/profile'");

  c = smallBag();
  c.samples.clear();
  const std::string no_samples = dir.file("no_samples.bag");
  writeBag(no_samples, c);
  expectMessageContains([&] { readBag(no_samples); }, no_samples,
                        "no sensor_msgs/JointState messages");

  c = smallBag();
  {
    // Only a message with nothing observed.
    rosbag::Bag bag(dir.file("nothing.bag"), rosbag::bagmode::Write);
    bag.write("road/profile", c.origin, roadProfileMessage(c.origin, 0, 0));
    sensor_msgs::JointState js;
    js.header.stamp = stampAt(c.origin, 0.1);
    js.name = {"left_suspension"};
    js.position = {std::numeric_limits<double>::quiet_NaN()};
    bag.write("suspension/joint_states", js.header.stamp, js);
  }
  expectMessageContains([&] { readBag(dir.file("nothing.bag")); }, dir.file("nothing.bag"),
                        "(no samples)");

  c = smallBag();
  c.samples.insert(c.samples.begin(), sample(-0.5, {0}, {1.0}));
  const std::string early = dir.file("early.bag");
  writeBag(early, c);
  expectMessageContains([&] { readBag(early); }, early,
                        "0.500000 s before the first 'road/profile' message");
}

TEST(BagErrors, AmbiguousOrMistypedTopicsAndDuplicateStamps) {
  ScratchDir dir;
  const BagContents c = smallBag();
  const std::string two = dir.file("two_roads.bag");
  {
    rosbag::Bag bag(two, rosbag::bagmode::Write);
    bag.write("/a/road/profile", c.origin, roadProfileMessage(c.origin, 0, 0));
    bag.write("/b/road/profile", c.origin, roadProfileMessage(c.origin, 0, 0));
    bag.write("suspension/joint_states", c.origin + ros::Duration(1.0),
              jointStateFromMeasurement(c.samples[0], c.origin + ros::Duration(1.0)));
  }
  expectMessageContains([&] { readBag(two); }, two, "several topics end in 'road/profile'");

  const std::string mistyped = dir.file("mistyped.bag");
  {
    rosbag::Bag bag(mistyped, rosbag::bagmode::Write);
    bag.write("road/profile", c.origin, jointStateFromMeasurement(c.samples[0], c.origin));
  }
  expectMessageContains([&] { readBag(mistyped); }, mistyped,
                        "has type sensor_msgs/JointState, expected pc_ekf/RoadProfile");

  const std::string dup = dir.file("dup.bag");
  {
    rosbag::Bag bag(dup, rosbag::bagmode::Write);
    bag.write("road/profile", c.origin, roadProfileMessage(c.origin, 0, 0));
    bag.write("road/profile", c.origin, roadProfileMessage(c.origin, 0.1, 0));
    bag.write("suspension/joint_states", c.origin,
              jointStateFromMeasurement(c.samples[0], c.origin));
  }
  expectMessageContains([&] { readBag(dup); }, dup,
                        "two 'road/profile' messages stamped 500.000000000");

  BagContents clash = smallBag();
  clash.samples.push_back(sample(1.0, {3}, {9}));  // channel v2 twice at t = 1
  const std::string clash_path = dir.file("clash.bag");
  writeBag(clash_path, clash);
  expectMessageContains([&] { readBag(clash_path); }, clash_path, "both observe channel 3");
}

TEST(BagErrors, WritingToAnUnwritablePathNamesIt) {
  const std::string path = "/nonexistent-dir/x.bag";
  expectMessageContains([&] { writeBag(path, smallBag()); }, path, "cannot write bag");
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
