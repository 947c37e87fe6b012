// EstimatorTimeline (time origin, ordering, pending samples, road bound),
// the rosparam conversion of ros_config, EstimatorRun's handling of a
// non-finite update and its derived quantities' cadence, without a running
// estimator.
#include <limits>

#include "estimator_test_support.h"
#include "pc_ekf/ros/estimator_run.h"
#include "pc_ekf/ros/estimator_timeline.h"
#include "pc_ekf/ros/ros_config.h"

namespace pc_ekf::test {
namespace {

// The road's height under its first contact at t.
double firstHeight(const ContactRoad& road, double t) {
  Eigen::VectorXd h(road.contactCount());
  road.heights(t, h);
  return h[0];
}

Measurement sample(double u1) {
  Measurement m;
  m.channels = {0 /* u1 */};
  m.values = Eigen::VectorXd::Constant(1, u1);
  return m;
}

TimelineSettings settings(bool topic_required) {
  TimelineSettings s;
  s.road_topic_required = topic_required;
  s.analytic_interval = 0.3;
  s.time_jump_tolerance = 0.5;
  s.road_wait_timeout = 1.0;
  s.max_pending = 3;
  s.max_road = 10;
  return s;
}

TEST(EstimatorTimeline, AnalyticOriginIsOneIntervalBeforeTheFirstSample) {
  EstimatorTimeline tl(settings(false));
  DroppedSamples dropped;
  EXPECT_EQ(tl.addSample(ros::Time(1000, 300000000), sample(1), 50.0), StampVerdict::kAccepted);
  EXPECT_TRUE(tl.release(50.9, &dropped).empty());  // may still get a road message
  EXPECT_EQ(tl.mode(), RoadMode::kUndecided);
  const auto first = tl.release(51.0, &dropped);
  ASSERT_EQ(first.size(), 1u);
  EXPECT_EQ(tl.mode(), RoadMode::kAnalytic);
  EXPECT_EQ(*tl.origin(), ros::Time(1000, 0));
  EXPECT_EQ(first[0].measurement.time, 0.3);
  EXPECT_FALSE(first[0].road_held);
  EXPECT_EQ(tl.addSample(ros::Time(1000, 600000000), sample(2), 51.1), StampVerdict::kAccepted);
  const auto second = tl.release(51.1, &dropped);  // no wait once analytic
  ASSERT_EQ(second.size(), 1u);
  EXPECT_EQ(second[0].measurement.time, 0.6);
  EXPECT_EQ(tl.addRoad(ros::Time(1000, 700000000), 0.0, 0.0, 51.2), StampVerdict::kIgnored);
}

TEST(EstimatorTimeline, RoadFreeReleasesTheFirstSampleAtOnceAndIgnoresRoads) {
  TimelineSettings s = settings(false);
  s.road_free = true;
  EstimatorTimeline tl(s);
  DroppedSamples dropped;
  // A road message before any sample does not make the run a topic run.
  EXPECT_EQ(tl.addRoad(ros::Time(1000, 100000000), 0.0, 0.0, 49.9), StampVerdict::kIgnored);
  EXPECT_EQ(tl.addSample(ros::Time(1000, 300000000), sample(1), 50.0), StampVerdict::kAccepted);
  const auto first = tl.release(50.0, &dropped);  // no wait for a road that is never used
  ASSERT_EQ(first.size(), 1u);
  EXPECT_EQ(tl.mode(), RoadMode::kAnalytic);
  EXPECT_EQ(*tl.origin(), ros::Time(1000, 0));  // the node's rule: one interval before
  EXPECT_EQ(first[0].measurement.time, 0.3);
  EXPECT_EQ(tl.roadCount(), 0u);
}

TEST(EstimatorTimeline, TopicRoadSetsTheOriginAndSamplesWaitForIt) {
  EstimatorTimeline tl(settings(true));
  DroppedSamples dropped;
  // A sample before the first road message is stamped before t = 0.
  EXPECT_EQ(tl.addSample(ros::Time(99, 0), sample(1), 1.0), StampVerdict::kAccepted);
  EXPECT_EQ(tl.addRoad(ros::Time(100, 0), 0.0, 0.0, 1.1), StampVerdict::kAccepted);
  EXPECT_EQ(tl.mode(), RoadMode::kTopic);
  EXPECT_EQ(*tl.origin(), ros::Time(100, 0));
  EXPECT_TRUE(tl.release(1.1, &dropped).empty());
  EXPECT_EQ(dropped.before_origin, 1);
  EXPECT_EQ(tl.addSample(ros::Time(99, 500000000), sample(1), 1.2), StampVerdict::kBeforeOrigin);
  EXPECT_EQ(tl.addSample(ros::Time(100, 20000000), sample(2), 1.2), StampVerdict::kAccepted);
  EXPECT_TRUE(tl.release(1.2, &dropped).empty());  // road only at t = 0
  EXPECT_EQ(tl.addRoad(ros::Time(100, 10000000), 0.01, 0.0, 1.3), StampVerdict::kAccepted);
  EXPECT_TRUE(tl.release(1.3, &dropped).empty());
  EXPECT_EQ(tl.addRoad(ros::Time(100, 20000000), 0.02, 0.0, 1.4), StampVerdict::kAccepted);
  const auto ready = tl.release(1.4, &dropped);
  ASSERT_EQ(ready.size(), 1u);
  EXPECT_EQ(ready[0].measurement.time, 0.02);
  EXPECT_FALSE(ready[0].road_held);
  EXPECT_EQ(firstHeight(*tl.road(), 0.015), 0.015);
  // Road stamps: duplicate, slightly back, far back, non-finite.
  EXPECT_EQ(tl.addRoad(ros::Time(100, 20000000), 0.0, 0.0, 1.5), StampVerdict::kDuplicate);
  EXPECT_EQ(tl.addRoad(ros::Time(100, 15000000), 0.0, 0.0, 1.5), StampVerdict::kOutOfOrder);
  EXPECT_EQ(tl.addRoad(ros::Time(99, 0), 0.0, 0.0, 1.5), StampVerdict::kTimeJump);
  EXPECT_EQ(tl.addRoad(ros::Time(101, 0), std::nan(""), 0.0, 1.5), StampVerdict::kNonFinite);
  EXPECT_EQ(tl.addSample(ros::Time(100, 20000000), sample(3), 1.5), StampVerdict::kDuplicate);
  EXPECT_EQ(tl.addSample(ros::Time(99, 0), sample(3), 1.5), StampVerdict::kTimeJump);
}

TEST(EstimatorTimeline, WaitCountsFromTheLastRoadMessageAndIsBounded) {
  EstimatorTimeline tl(settings(true));
  DroppedSamples dropped;
  ASSERT_EQ(tl.addRoad(ros::Time(100, 0), 0.0, 0.0, 10.0), StampVerdict::kAccepted);
  ASSERT_EQ(tl.addSample(ros::Time(101, 0), sample(1), 10.0), StampVerdict::kAccepted);
  ASSERT_EQ(tl.addRoad(ros::Time(100, 500000000), 0.0, 0.0, 10.8), StampVerdict::kAccepted);
  EXPECT_TRUE(tl.release(11.5, &dropped).empty());  // 1.5 s since arrival, 0.7 since road
  const auto held = tl.release(11.8, &dropped);
  ASSERT_EQ(held.size(), 1u);
  EXPECT_TRUE(held[0].road_held);
  // More than max_pending (3) waiting: the oldest goes, road held.
  for (int i = 1; i <= 4; ++i) {
    ASSERT_EQ(tl.addSample(ros::Time(101, i * 1000000), sample(i), 12.0), StampVerdict::kAccepted);
  }
  const auto forced = tl.release(12.0, &dropped);
  ASSERT_EQ(forced.size(), 1u);
  EXPECT_EQ(forced[0].stamp, ros::Time(101, 1000000));
  EXPECT_EQ(tl.pendingCount(), 3u);
}

TEST(EstimatorTimeline, NoRoadMessageWithTopicRoadDropsTheSample) {
  EstimatorTimeline tl(settings(true));
  DroppedSamples dropped;
  ASSERT_EQ(tl.addSample(ros::Time(5, 0), sample(1), 0.0), StampVerdict::kAccepted);
  EXPECT_TRUE(tl.release(1.0, &dropped).empty());
  EXPECT_EQ(dropped.no_road, 1);
  EXPECT_EQ(tl.mode(), RoadMode::kUndecided);
}

TEST(EstimatorTimeline, RoadBufferIsBoundedAndResetStartsOver) {
  EstimatorTimeline tl(settings(true));
  for (int i = 0; i <= 10; ++i) {
    ASSERT_EQ(tl.addRoad(ros::Time(100, i * 1000000), i, i, 0.0), StampVerdict::kAccepted);
  }
  EXPECT_TRUE(tl.roadHistoryComplete());  // nothing needed is droppable yet (t = 0)
  tl.keepRoadFrom(0.0075);
  ASSERT_EQ(tl.addRoad(ros::Time(100, 11000000), 11, 11, 0.0), StampVerdict::kAccepted);
  EXPECT_FALSE(tl.roadHistoryComplete());
  EXPECT_EQ(tl.roadCount(), 5u);  // 0.007 (kept for interpolation) .. 0.011
  EXPECT_DOUBLE_EQ(firstHeight(*tl.road(), 0.0075), 7.5);
  tl.reset();
  EXPECT_EQ(tl.mode(), RoadMode::kUndecided);
  EXPECT_FALSE(tl.origin());
  EXPECT_TRUE(tl.roadHistoryComplete());
  EXPECT_EQ(tl.roadCount(), 0u);
  EXPECT_EQ(tl.addRoad(ros::Time(50, 0), 0.0, 0.0, 0.0), StampVerdict::kAccepted);  // re-armed
}

TEST(RosConfig, ParameterValuesBecomeExactYaml) {
  XmlRpc::XmlRpcValue v;
  v["a"] = 0.1;
  v["b"] = 1.0 / 3.0;
  v["c"] = true;
  v["d"] = 7;
  v["e"][0] = std::string("u1");
  v["e"][1] = std::string("v2");
  v["f"]["g"] = 1e-12;
  const YAML::Node y = yamlFromXmlRpc(v);
  EXPECT_EQ(y["a"].Scalar(), "0.1");
  EXPECT_EQ(std::stod(y["b"].Scalar()), 1.0 / 3.0);
  EXPECT_EQ(y["c"].Scalar(), "true");
  EXPECT_EQ(y["d"].Scalar(), "7");
  ASSERT_TRUE(y["e"].IsSequence());
  EXPECT_EQ(y["e"][1].Scalar(), "v2");
  EXPECT_EQ(std::stod(y["f"]["g"].Scalar()), 1e-12);
}

TEST(RosConfig, MergeOverridesKeyByKey) {
  YAML::Node base = YAML::Load("{a: {x: 1, y: 2}, b: [1, 2], c: 3}");
  mergeYaml(base, YAML::Load("{a: {y: 5, z: 6}, b: [9], d: 4}"));
  EXPECT_EQ(base["a"]["x"].as<int>(), 1);
  EXPECT_EQ(base["a"]["y"].as<int>(), 5);
  EXPECT_EQ(base["a"]["z"].as<int>(), 6);
  EXPECT_EQ(base["b"].size(), 1u);  // lists are replaced, not merged
  EXPECT_EQ(base["c"].as<int>(), 3);
  EXPECT_EQ(base["d"].as<int>(), 4);
}

TEST(EstimatorRun, NonFiniteUpdateIsReportedNotPublishedAsNan) {
  EstimatorConfig config = loadConfigFile(configPath("speed_bump.yaml"));
  config.node.coherence_check = false;
  const auto propagator = makePropagator(config, makeModel(config, makeRoad(config)));
  const Record record = syntheticRecord(config, 1);
  EstimatorRun run(config, propagator, false);
  const SampleEstimate first = run.process(record.samples[0], ros::Time(1, 0));
  ASSERT_FALSE(first.non_finite);

  // R = (r_relative z)^2 overflows for z = 1e300: the update is not finite.
  Measurement huge = record.samples[1];
  huge.values.setConstant(1e300);
  const SampleEstimate bad = run.process(huge, ros::Time(2, 0));
  EXPECT_TRUE(bad.non_finite);
  EXPECT_TRUE(bad.estimate.non_finite);
  EXPECT_FALSE(bad.estimate.healthy);
  EXPECT_EQ(bad.estimate.sample_index, 2u);
  EXPECT_EQ(bad.estimate.mean, first.estimate.mean);  // the state before the sample
  for (double v : bad.estimate.coefficients) EXPECT_TRUE(std::isfinite(v));
  for (double v : {bad.estimate.nis, bad.estimate.nis_window_mean}) EXPECT_TRUE(std::isfinite(v));
  EXPECT_FALSE(bad.estimate.warnings.empty());

  // The filter carries on from its state before the bad sample.
  const SampleEstimate next = run.process(record.samples[2], ros::Time(3, 0));
  EXPECT_FALSE(next.non_finite);
  EXPECT_EQ(next.estimate.sample_index, 3u);
  EstimatorRun skipped(config, propagator, false);
  skipped.process(record.samples[0], ros::Time(1, 0));
  const SampleEstimate reference = skipped.process(record.samples[2], ros::Time(3, 0));
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_NEAR(next.estimate.mean[i], reference.estimate.mean[i],
                1e-12 * std::abs(reference.estimate.mean[i]));
  }
  EXPECT_FALSE(run.batch(false).ok);  // road history gone: refused
}

// The derived quantities' cadence: projected at the first sample, every
// node.derived_every-th and at every PDF; the estimates between carry the
// latest projection, with the sample it was made at.
TEST(EstimatorRun, DerivedQuantitiesAreProjectedAtTheirCadence) {
  EstimatorConfig config = loadConfigFile(configPath("turns.yaml"));
  config.node.coherence_check = false;
  config.node.derived_every = 4;
  config.node.pdf_every = 7;
  const auto propagator = makePropagator(config, makeModel(config, makeRoad(config)));
  const Record record = syntheticRecord(config, 3);
  EstimatorRun run(config, propagator, true);
  std::vector<std::uint32_t> projected_at;
  std::vector<double> projected;  // the latest projection's cg_height coefficients
  for (int k = 0; k < 9; ++k) {
    const SampleEstimate e = run.process(record.samples[k], ros::Time(1 + k, 0));
    ASSERT_EQ(e.estimate.sample_index, static_cast<std::uint32_t>(k + 1));
    ASSERT_EQ(e.estimate.derived_names.size(), 3u);
    projected_at.push_back(e.estimate.derived_sample_index);
    if (e.estimate.derived_sample_index == e.estimate.sample_index) {
      // This estimate's own expansions, as a single projection gives them.
      Eigen::MatrixXd c(propagator->parameterCount(), e.estimate.term_count);
      for (Eigen::Index i = 0; i < c.rows(); ++i) {
        for (Eigen::Index j = 0; j < c.cols(); ++j) {
          c(i, j) = e.estimate.coefficients[i * c.cols() + j];
        }
      }
      const DerivedExpansions d =
          rolloverExpansions(propagator->mapping(), propagator->basis(), c);
      for (Eigen::Index j = 0; j < c.cols(); ++j) {
        EXPECT_EQ(e.estimate.derived_coefficients[j], d.coefficients(0, j)) << "term " << j;
      }
    }
    const std::vector<double> cg(e.estimate.derived_coefficients.begin(),
                                 e.estimate.derived_coefficients.begin() + e.estimate.term_count);
    if (e.estimate.derived_sample_index != e.estimate.sample_index) {
      EXPECT_EQ(cg, projected) << "sample " << k + 1 << " carries the latest projection";
    }
    projected = cg;
    if (e.pdf) {  // a PDF's derived quantities are its own sample's
      EXPECT_EQ(e.estimate.derived_sample_index, e.estimate.sample_index);
      EXPECT_EQ(e.pdf->derived.row(0).transpose(),
                Eigen::Map<const Eigen::VectorXd>(cg.data(), static_cast<Eigen::Index>(cg.size())));
    }
  }
  // First sample, every 4th, and the PDF at 7.
  EXPECT_EQ(projected_at, (std::vector<std::uint32_t>{1, 1, 1, 4, 4, 4, 7, 8, 8}));
  EXPECT_EQ(run.priorEstimate(ros::Time(20, 0)).derived_sample_index, 0u);
}

}  // namespace
}  // namespace pc_ekf::test

int main(int argc, char** argv) {
  return pc_ekf::test::runRostests(argc, argv, "estimator_components_tester");
}
