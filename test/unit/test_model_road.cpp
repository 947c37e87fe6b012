// Road inputs of docs/method.md §1.5: bump shape, kinks, sine, sampled series.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "pc_ekf/model/road_input.h"

namespace pc_ekf {
namespace {

void expectTimes(const std::vector<double>& got, const std::vector<double>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i) EXPECT_NEAR(got[i], want[i], 1e-12) << i;
}

TEST(SpeedBumpRoad, HeightsAtKnownTimes) {
  const SpeedBumpRoad road{SpeedBumpSettings()};  // 16 km/h = 4.444 m/s, 3 m bump
  const double tol = 1e-12;
  EXPECT_NEAR(road.height(-0.1)[0], 0.0, tol);
  // t = 0.1125 s: 0.5 m of travel, half way up the ramp; tyre 2 starts at 0.135 s.
  EXPECT_NEAR(road.height(0.1125)[0], 0.05, tol);
  EXPECT_EQ(road.height(0.1125)[1], 0.0);
  EXPECT_EQ(road.height(0.13)[1], 0.0);
  // t = 0.3 s: 1.333 m, on the flat; tyre 2 at 0.733 m up its ramp.
  EXPECT_NEAR(road.height(0.3)[0], 0.10, tol);
  EXPECT_NEAR(road.height(0.3)[1], 0.08 * (4.0 / 3.0 - 0.6), tol);
  // t = 0.5 s: 2.222 m, ramping down; tyre 2 on its flat.
  EXPECT_NEAR(road.height(0.5)[0], 0.10 * (3.0 - 20.0 / 9.0), tol);
  EXPECT_NEAR(road.height(0.5)[1], 0.08, tol);
  // t = 0.7 s: tyre 1 past the bump (ends at 0.675 s), tyre 2 ramping down.
  EXPECT_EQ(road.height(0.7)[0], 0.0);
  EXPECT_NEAR(road.height(0.7)[1], 0.08 * (3.6 - 0.7 * 40.0 / 9.0), tol);
  EXPECT_EQ(road.height(0.9), Eigen::Vector2d::Zero());
}

TEST(SpeedBumpRoad, BreakpointsOfBothTyres) {
  const SpeedBumpRoad road{SpeedBumpSettings()};
  expectTimes(road.breakpoints(0.0, 1.0), {0.135, 0.225, 0.36, 0.45, 0.585, 0.675, 0.81});
  expectTimes(road.breakpoints(-1.0, 0.3), {0.0, 0.135, 0.225});
  expectTimes(road.breakpoints(0.3, 0.6), {0.36, 0.45, 0.585});
  EXPECT_TRUE(road.breakpoints(0.81, 3.0).empty());  // open interval
  EXPECT_TRUE(road.breakpoints(0.0, 0.1).empty());
}

TEST(SpeedBumpRoad, SettingsShiftAndScale) {
  SpeedBumpSettings s;
  s.start_distance = 1.0;  // 0.225 s later
  s.height_right = 0.05;
  s.delay_fraction = 0.0;
  s.ramp_up_length = 0.0;  // a step up: both corners coincide
  const SpeedBumpRoad road(s);
  EXPECT_EQ(road.height(0.2)[0], 0.0);
  EXPECT_NEAR(road.height(0.25)[0], 0.10, 1e-12);
  EXPECT_NEAR(road.height(0.25)[1], 0.05, 1e-12);
  expectTimes(road.breakpoints(0.0, 2.0), {0.225, 0.45, 0.675});
  s.speed_kmh = 0.0;
  EXPECT_THROW(SpeedBumpRoad{s}, std::invalid_argument);
}

TEST(SineRoad, OutOfPhase) {
  const SineRoad road{SineSettings()};
  EXPECT_NEAR(road.height(0.25)[0], 0.05, 1e-15);
  EXPECT_NEAR(road.height(0.25)[1], -0.05, 1e-15);
  EXPECT_NEAR(road.height(1.0 / 12.0)[0], 0.025, 1e-15);
  EXPECT_TRUE(road.breakpoints(0.0, 3.0).empty());
  SineSettings s;
  s.right_sign = 1.0;
  s.frequency = 2.0;
  EXPECT_NEAR(SineRoad(s).height(0.125)[1], 0.05, 1e-15);
}

// Heights of a two-contact road at t.
Eigen::Vector2d at(const ContactRoad& road, double t) {
  Eigen::Vector2d h;
  road.heights(t, h);
  return h;
}

SampledRoad threeSamples() {
  return SampledRoad({0.0, 1.0, 2.0}, {{0.0, 1.0, 0.0}, {0.0, -2.0, -2.0}});
}

TEST(SampledRoad, LinearInterpolationHeldOutside) {
  const SampledRoad road = threeSamples();
  EXPECT_EQ(at(road, 0.5), Eigen::Vector2d(0.5, -1.0));
  EXPECT_EQ(at(road, 1.0), Eigen::Vector2d(1.0, -2.0));
  EXPECT_NEAR(at(road, 1.75)[0], 0.25, 1e-15);
  EXPECT_EQ(at(road, 1.75)[1], -2.0);
  EXPECT_EQ(at(road, -3.0), Eigen::Vector2d(0.0, 0.0));
  EXPECT_EQ(at(road, 7.0), Eigen::Vector2d(0.0, -2.0));
  expectTimes(road.breakpoints(0.0, 2.0), {1.0});
  expectTimes(road.breakpoints(-1.0, 5.0), {0.0, 1.0, 2.0});
  EXPECT_TRUE(road.breakpoints(0.2, 1.0).empty());
  EXPECT_EQ(at(SampledRoad(2), 1.0), Eigen::Vector2d::Zero());
}

TEST(SampledRoad, AppendRejectsBadSamplesNamingTheTime) {
  SampledRoad road = threeSamples();
  try {
    road.append(1.5, {0.0, 0.0});
    FAIL() << "time going backwards accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("t = 1.5"), std::string::npos) << e.what();
  }
  EXPECT_THROW(road.append(2.0, {0.0, 0.0}), std::invalid_argument);  // not strictly after
  EXPECT_THROW(road.append(3.0, {std::nan(""), 0.0}), std::invalid_argument);
  EXPECT_THROW(road.append(3.0, {0.0, std::numeric_limits<double>::infinity()}),
               std::invalid_argument);
  EXPECT_THROW(road.append(std::nan(""), {0.0, 0.0}), std::invalid_argument);
  EXPECT_EQ(road.size(), 3u);
  road.append(3.0, {2.0, 0.0});
  EXPECT_EQ(road.lastTime(), 3.0);
  EXPECT_EQ(at(road, 2.5), Eigen::Vector2d(1.0, -1.0));
  EXPECT_THROW(SampledRoad({0.0, 1.0}, {{0.0}, {0.0, 0.0}}), std::invalid_argument);
  EXPECT_THROW(SampledRoad({1.0, 0.0}, {{0.0, 0.0}, {0.0, 0.0}}), std::invalid_argument);
  EXPECT_THROW(SampledRoad(2).firstTime(), std::logic_error);
}

TEST(SampledRoad, DiscardKeepsTheSampleAtOrBefore) {
  SampledRoad road = threeSamples();
  road.discardBefore(-1.0);
  EXPECT_EQ(road.size(), 3u);
  road.discardBefore(1.0);
  EXPECT_EQ(road.size(), 2u);
  EXPECT_EQ(road.firstTime(), 1.0);
  road.discardBefore(1.5);
  EXPECT_EQ(road.size(), 2u);
  EXPECT_EQ(at(road, 1.5), Eigen::Vector2d(0.5, -2.0));  // interpolation still possible
  road.discardBefore(10.0);
  EXPECT_EQ(road.size(), 1u);
  EXPECT_EQ(road.firstTime(), 2.0);
}

// ---------------------------------------------------------------- course

CourseSegment bumpSegment() {
  CourseSegment s;
  s.type = CourseSegment::Type::kSpeedBump;
  return s;
}

CourseSegment timedSegment(CourseSegment::Type type, double duration) {
  CourseSegment s;
  s.type = type;
  s.duration = duration;
  return s;
}

TEST(CourseRoad, BumpsAreTheSingleBumpShiftedInTime) {
  // Bump (0.81 s at 16 km/h), 9.19 s flat, bump, 3 s flat.
  const CourseRoad course({bumpSegment(), timedSegment(CourseSegment::Type::kRest, 9.19),
                           bumpSegment(), timedSegment(CourseSegment::Type::kRest, 3.0)});
  const SpeedBumpRoad bump{SpeedBumpSettings()};
  ASSERT_EQ(course.boundaries().size(), 5u);
  EXPECT_NEAR(course.boundaries()[1], 0.81, 1e-12);
  EXPECT_NEAR(course.boundaries()[2], 10.0, 1e-12);
  EXPECT_NEAR(course.boundaries()[4], 13.81, 1e-12);
  const double start2 = course.boundaries()[2];
  for (double t = 0.0; t < 14.5; t += 0.0137) {
    const Eigen::Vector2d got = course.height(t);
    Eigen::Vector2d want = Eigen::Vector2d::Zero();
    if (t < 0.81) want = bump.height(t);
    if (t >= start2 && t < start2 + 0.81) want = bump.height(t - start2);
    EXPECT_EQ(got, want) << t;
  }
  EXPECT_NEAR(course.height(start2 + 0.3)[0], 0.10, 1e-12);
  EXPECT_NEAR(course.height(start2 + 0.3)[1], 0.08 * (4.0 / 3.0 - 0.6), 1e-12);
  EXPECT_EQ(course.height(5.0), Eigen::Vector2d::Zero());
}

TEST(CourseRoad, BreakpointsIncludeSegmentBoundariesAndShiftedCorners) {
  const CourseRoad course({bumpSegment(), timedSegment(CourseSegment::Type::kRest, 9.19),
                           bumpSegment(), timedSegment(CourseSegment::Type::kRest, 3.0)});
  // First bump's corners (0.81 = its end = a boundary, listed once), then the
  // second bump's shifted by 10 s and the course's end.
  expectTimes(course.breakpoints(0.0, 20.0),
              {0.135, 0.225, 0.36, 0.45, 0.585, 0.675, 0.81, 10.0, 10.135, 10.225, 10.36, 10.45,
               10.585, 10.675, 10.81, 13.81});
  expectTimes(course.breakpoints(5.0, 10.3), {10.0, 10.135, 10.225});
  EXPECT_TRUE(course.breakpoints(1.0, 9.9).empty());
}

TEST(CourseRoad, SineStartsAtPhaseZeroAndItsEndIsABreakpoint) {
  CourseSegment sine = timedSegment(CourseSegment::Type::kSine, 1.25);
  sine.sine.amplitude = 0.02;
  sine.sine.frequency = 1.0;
  const CourseRoad course({timedSegment(CourseSegment::Type::kRest, 2.0), sine});
  EXPECT_EQ(course.height(1.9), Eigen::Vector2d::Zero());
  EXPECT_EQ(course.height(2.0)[0], 0.0);
  EXPECT_NEAR(course.height(2.25)[0], 0.02, 1e-12);   // quarter period in
  EXPECT_NEAR(course.height(2.25)[1], -0.02, 1e-12);  // right_sign -1
  EXPECT_NEAR(course.height(3.2)[0], 0.02 * std::sin(2.0 * M_PI * 1.2), 1e-12);
  EXPECT_EQ(course.height(3.25), Eigen::Vector2d::Zero());  // after the course: flat
  expectTimes(course.breakpoints(0.0, 5.0), {2.0, 3.25});
}

TEST(CourseRoad, RefusesAnEmptyCourseAndNonPositiveDurations) {
  EXPECT_THROW(CourseRoad(std::vector<CourseSegment>{}), std::invalid_argument);
  EXPECT_THROW(CourseRoad({timedSegment(CourseSegment::Type::kRest, 0.0)}), std::invalid_argument);
  EXPECT_THROW(CourseRoad({timedSegment(CourseSegment::Type::kSine, -1.0)}), std::invalid_argument);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
