// Lateral manoeuvres in a course (road_input.h, course_motion.h): a_y against
// closed forms (V^2 / R, a lane change's offset, the slalom's sine), speeds
// and yaw rates (a_y = V psi'), the road under them, and a synthetic drive
// that records speed and gyro_z.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "pc_ekf/io/estimator_config.h"
#include "pc_ekf/model/course_motion.h"
#include "pc_ekf/model/integrator.h"
#include "pc_ekf/model/roll_plane_model.h"

namespace pc_ekf {
namespace {

constexpr double kPi = 3.14159265358979323846;

CourseSegment manoeuvre(CourseSegment::Type type, double duration, double speed_kmh) {
  CourseSegment s;
  s.type = type;
  s.duration = duration;
  s.speed_kmh = speed_kmh;
  return s;
}

CourseSegment rest(double duration) {
  CourseSegment s;
  s.duration = duration;
  return s;
}

// A right turn of radius 25 m at 36 km/h: a_y = -V^2 / R after the ramp,
// half of it midway up the ramp, 0 at its ends; the ramp's ends are breakpoints.
TEST(CourseMotion, TurnReachesVSquaredOverRadius) {
  CourseSegment turn = manoeuvre(CourseSegment::Type::kTurn, 4.0, 36.0);
  turn.manoeuvre.radius = -25.0;
  turn.manoeuvre.ramp = 1.0;
  const CourseRoad road({rest(0.5), turn, rest(1.0)});
  const HorizontalMotion* m = road.horizontalMotion();
  ASSERT_NE(m, nullptr);
  EXPECT_TRUE(m->accelerates());
  EXPECT_NEAR(m->at(2.5).lateral, -100.0 / 25.0, 1e-12);
  EXPECT_NEAR(m->at(2.5).speed, 10.0, 1e-12);
  EXPECT_NEAR(m->at(2.5).yaw_rate, -0.4, 1e-12);  // V / R
  EXPECT_NEAR(m->at(1.0).lateral, -2.0, 1e-12);   // half-way up the ramp
  EXPECT_EQ(m->at(0.25).lateral, 0.0);            // standing before it
  EXPECT_EQ(m->at(0.25).speed, 0.0);
  EXPECT_NEAR(m->at(4.5 - 1e-9).lateral, 0.0, 1e-8);
  EXPECT_EQ(m->at(5.0).speed, 0.0);
  const std::vector<double> b = road.breakpoints(0.0, 10.0);
  for (double t : {0.5, 1.5, 3.5, 4.5}) {
    EXPECT_NE(std::find(b.begin(), b.end(), t), b.end()) << t;
  }
  // Flat: the road holds its level (0) under the turn.
  EXPECT_EQ(road.height(2.0), Eigen::Vector2d::Zero());
}

// One lane change: a_y = A sin(2 pi t / T) returns the heading to where it was
// (the integral of a_y is 0) after moving the vehicle sideways by A T^2 / (2 pi).
TEST(CourseMotion, LaneChangeOffsetsOneLane) {
  CourseSegment change = manoeuvre(CourseSegment::Type::kLaneChange, 2.5, 80.0);
  change.manoeuvre.lateral_acceleration = 4.0;
  const CourseMotion m({change}, {0.0, 2.5});
  double v = 0.0, y = 0.0;
  const int n = 20000;
  const double h = 2.5 / n;
  for (int k = 0; k < n; ++k) {  // midpoint rule for v, trapezoid for y
    const double v_next = v + h * m.at((k + 0.5) * h).lateral;
    y += 0.5 * h * (v + v_next);
    v = v_next;
  }
  EXPECT_NEAR(v, 0.0, 1e-9);
  EXPECT_NEAR(y, 4.0 * 2.5 * 2.5 / (2.0 * kPi), 1e-6);
  EXPECT_NEAR(m.at(2.5 / 4.0).lateral, 4.0, 1e-12);  // the peak, a quarter in
}

TEST(CourseMotion, SlalomIsASineAndAStraightCourseDoesNotAccelerate) {
  CourseSegment slalom = manoeuvre(CourseSegment::Type::kSlalom, 4.0, 50.0);
  slalom.manoeuvre.lateral_acceleration = 3.5;
  slalom.manoeuvre.frequency = 0.5;
  const CourseMotion m({slalom}, {0.0, 4.0});
  for (double t : {0.3, 1.1, 2.7}) {
    EXPECT_NEAR(m.at(t).lateral, 3.5 * std::sin(kPi * t), 1e-12);
    EXPECT_NEAR(m.at(t).yaw_rate * 50.0 / 3.6, m.at(t).lateral, 1e-12);
  }
  CourseSegment bump;
  bump.type = CourseSegment::Type::kSpeedBump;
  const CourseRoad straight({bump, rest(1.0)});
  ASSERT_NE(straight.horizontalMotion(), nullptr);
  EXPECT_FALSE(straight.horizontalMotion()->accelerates());
  EXPECT_NEAR(straight.horizontalMotion()->at(0.1).speed, 16.0 / 3.6, 1e-12);
  CourseSegment bad = slalom;
  bad.manoeuvre.frequency = 0.0;
  EXPECT_THROW(CourseRoad({bad}), std::invalid_argument);
}

// A turn on an ISO 8608 surface is that road, blended in from the level.
TEST(CourseMotion, RoughSurfaceIsTheIsoRoad) {
  CourseSegment turn = manoeuvre(CourseSegment::Type::kTurn, 3.0, 36.0);
  turn.manoeuvre.rough = true;
  CourseSegment iso = manoeuvre(CourseSegment::Type::kIso8608, 3.0, 36.0);
  const CourseRoad a({turn}), b({iso});
  for (double t : {0.1, 1.3, 2.9}) EXPECT_EQ(a.height(t), b.height(t));
  EXPECT_GT(std::abs(a.height(1.3)[0]), 0.0);
}

// A slalom on a measured profile: the profile at start + V tau, shifted to
// begin where the ISO segment before it left the road; the profile's kinks are
// breakpoints at the times the wheels reach them (under a braking too), and
// the segment leaves the heights where it ended.
TEST(CourseMotion, MeasuredSurfaceIsTheProfileFromTheLevel) {
  const std::string path = ::testing::TempDir() + "/course_measured_profile.csv";
  {
    std::ofstream f(path);
    f << "s,left,right\n0,0.01,-0.02\n10,0.03,0.00\n20,0.00,0.05\n200,0.02,0.01\n";
  }
  const EstimatorConfig c = parseConfigString(
      "uncertain: [{name: added_mass, relative_range: 0.5}]\n"
      "road:\n"
      "  source: course\n"
      "  iso8608: {class: B, seed: 4}\n"
      "  course:\n"
      "    - {type: iso8608, duration: 1.0, speed_kmh: 36.0}\n"
      "    - {type: slalom, duration: 4.0, speed_kmh: 36.0, surface: profile, file: " + path +
          ", start: 5.0}\n"
      "    - {type: brake, duration: 2.0, speed_kmh: 36.0, deceleration: 2.0, surface: profile,\n"
      "       file: " + path + "}\n",
      "measured.yaml");
  ASSERT_EQ(c.road.course.size(), 3u);
  ASSERT_TRUE(c.road.course[1].manoeuvre.measured);
  EXPECT_FALSE(c.road.course[1].manoeuvre.rough);
  EXPECT_EQ(c.road.course[1].manoeuvre.profile_start, 5.0);
  const CourseRoad road(c.road.course);
  const Eigen::Vector2d level = road.levels()[1];
  EXPECT_GT(level.norm(), 0.0);
  const auto profile = [](double s) {  // the CSV, interpolated by hand
    const double x[] = {0, 10, 20, 200}, l[] = {0.01, 0.03, 0.00, 0.02}, r[] = {-0.02, 0.0, 0.05, 0.01};
    int i = s < 10 ? 0 : s < 20 ? 1 : 2;
    const double w = (s - x[i]) / (x[i + 1] - x[i]);
    return Eigen::Vector2d((1 - w) * l[i] + w * l[i + 1], (1 - w) * r[i] + w * r[i + 1]);
  };
  for (double tau : {0.0, 0.3, 0.5, 1.7, 3.9}) {
    const Eigen::Vector2d want = profile(5.0 + 10.0 * tau) - profile(5.0) + level;
    EXPECT_NEAR((road.height(1.0 + tau) - want).norm(), 0.0, 1e-15) << tau;
  }
  // Kinks at s = 10 and 20 m: 0.5 s and 1.5 s into the slalom.
  const std::vector<double> b = road.breakpoints(1.01, 4.9);
  EXPECT_NE(std::find_if(b.begin(), b.end(), [](double t) { return std::abs(t - 1.5) < 1e-12; }), b.end());
  EXPECT_NE(std::find_if(b.begin(), b.end(), [](double t) { return std::abs(t - 2.5) < 1e-12; }), b.end());
  // Braking from 10 m/s at 2 m/s^2: s = 10 m at tau = (10 - sqrt(100 - 40)) / 2 = 1.127 s.
  const Eigen::Vector2d level2 = road.levels()[2];
  const double tau = (10.0 - std::sqrt(100.0 - 40.0)) / 2.0;
  const std::vector<double> b2 = road.breakpoints(5.01, 6.99);
  EXPECT_NE(std::find_if(b2.begin(), b2.end(), [&](double t) { return std::abs(t - 5.0 - tau) < 1e-12; }),
            b2.end());
  const double s = 10.0 * 1.5 - 0.5 * 2.0 * 1.5 * 1.5;
  EXPECT_NEAR((road.height(6.5) - (profile(s) - profile(0.0) + level2)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((level2 - (profile(45.0) - profile(5.0) + level)).norm(), 0.0, 1e-15);
  // A file that is not there is named with its key.
  try {
    parseConfigString("uncertain: [{name: added_mass, relative_range: 0.5}]\n"
                      "road: {source: course, course: [{type: turn, duration: 1.0, surface: profile, "
                      "file: /nonexistent/road.csv}]}\n",
                      "bad.yaml");
    ADD_FAILURE() << "no error";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("road.course[0].file"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("/nonexistent/road.csv"), std::string::npos) << e.what();
  }
}

// The config's course keys, and a synthetic drive of it recording speed and
// gyro_z (the drive's, at every point) next to the suspension.
TEST(CourseMotion, ConfiguredTurnsAreRecordedAsSpeedAndYawRate) {
  const EstimatorConfig c = parseConfigString(
      "uncertain: [{name: added_mass, relative_range: 0.5}]\n"
      "road:\n"
      "  source: course\n"
      "  course:\n"
      "    - {type: turn, duration: 3.0, radius: 40.0, speed_kmh: 54.0, ramp: 0.5}\n"
      "    - {type: slalom, duration: 2.0, frequency: 0.8, lateral_acceleration: -2.0,\n"
      "       surface: iso8608, class: C}\n"
      "measurement: {channels: [u1, u2, v1, v2, speed, gyro_z]}\n",
      "turns.yaml");
  ASSERT_EQ(c.road.course.size(), 2u);
  EXPECT_EQ(c.road.course[0].type, CourseSegment::Type::kTurn);
  EXPECT_EQ(c.road.course[0].manoeuvre.radius, 40.0);
  EXPECT_EQ(c.road.course[0].manoeuvre.ramp, 0.5);
  EXPECT_FALSE(c.road.course[0].manoeuvre.rough);
  EXPECT_EQ(c.road.course[1].type, CourseSegment::Type::kSlalom);
  EXPECT_EQ(c.road.course[1].manoeuvre.frequency, 0.8);
  EXPECT_TRUE(c.road.course[1].manoeuvre.rough);
  EXPECT_EQ(c.road.course[1].iso8608.road_class, 'C');
  EXPECT_THROW(parseConfigString("uncertain: [{name: added_mass, relative_range: 0.5}]\n"
                                 "road: {source: course, course: [{type: turn, duration: 1.0, "
                                 "surface: gravel}]}\n",
                                 "bad.yaml"),
               std::exception);

  VehicleParameters p;
  p.body_cg_height = 0.25;
  p.added_mass_height = 0.4;
  const auto road = std::make_shared<CourseRoad>(c.road.course);
  const RollPlaneModel model(p, road, c.measurement.readings(rollPlaneDescription()));
  ASSERT_EQ(model.channelNames()[7], "speed");
  ASSERT_EQ(model.channelNames()[8], "gyro_z");
  const auto batch = model.prepare(p.toVector());
  Eigen::ArrayXXd y = batch->initialState();
  integrate(model, *batch, 0.0, 2.0, y, IntegratorSettings());
  const Eigen::VectorXd z = model.observationMatrix() * y.matrix().col(0);
  EXPECT_NEAR(z[7], 15.0, 1e-12);
  EXPECT_NEAR(z[8], 15.0 / 40.0, 1e-12);  // V / R
  EXPECT_GT(z[0] - z[1], 1e-3);           // a left turn: the left side extends
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
