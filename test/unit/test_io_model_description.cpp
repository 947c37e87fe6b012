// The parameter tables and model descriptions: the domains a table states are
// the ones its checks, its YAML reader and its doc table apply, and each
// built-in model's typed view, vector and description agree.
#include <gtest/gtest.h>

#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include "pc_ekf/io/estimator_config.h"
#include "pc_ekf/model/full_car_model.h"
#include "pc_ekf/model/roll_plane_model.h"

namespace pc_ekf {
namespace {

ParameterTable smallTable() {
  ParameterDomain capped = positive();
  capped.upper = 5.0;
  return ParameterTable({{"length", "m", 2.0, positive(), "a length"},
                         {"width", "m", 1.0, positive(), "a width"},
                         {"damping", "N s/m", 3.0, nonNegative(), "may be zero"},
                         {"offset", "m", 0.5, withinSumOf({"length", "width"}), "in [0, L + W]"},
                         {"gain", "", 1.0, capped, "in (0, 5]"},
                         {"shift", "m", -1.0, anyValue(), "any real"}});
}

TEST(ParameterTable, ViolationsNameTheEntryAndTheBound) {
  const ParameterTable t = smallTable();
  Eigen::VectorXd v = t.defaults();
  EXPECT_EQ(v, (Eigen::VectorXd(6) << 2.0, 1.0, 3.0, 0.5, 1.0, -1.0).finished());
  EXPECT_EQ(t.violation(v), "");
  EXPECT_EQ(t.violation(v.head(5)), "expected 6 parameters, got 5");
  const auto with = [&](int i, double x) {
    Eigen::VectorXd w = v;
    w[i] = x;
    return t.violation(w);
  };
  EXPECT_EQ(with(0, 0.0), "length = 0 must be > 0");
  EXPECT_EQ(with(2, 0.0), "");
  EXPECT_EQ(with(2, -0.5), "damping = -0.5 must be >= 0");
  EXPECT_EQ(with(3, 3.0), "");  // the end L + W = 3 is admissible
  EXPECT_EQ(with(3, 3.25), "offset = 3.25 outside [0, 3]");
  EXPECT_EQ(with(3, -0.25), "offset = -0.25 outside [0, 3]");
  EXPECT_EQ(with(4, 5.5), "gain = 5.5 outside (0, 5]");
  EXPECT_EQ(with(5, -1e300), "");
  EXPECT_EQ(with(5, std::numeric_limits<double>::infinity()), "shift = inf is not finite");
  // Open lower bounds are reported before closed ones, whatever the order.
  Eigen::VectorXd two = v;
  two[2] = -1.0;
  two[1] = -1.0;
  EXPECT_EQ(t.violation(two), "width = -1 must be > 0");
}

TEST(ParameterTable, FastCheckAgreesWithTheDetailedOne) {
  const ParameterTable t = smallTable();
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 6.0);
  int admissible = 0;
  for (int k = 0; k < 20000; ++k) {
    Eigen::VectorXd v(6);
    for (int i = 0; i < 6; ++i) v[i] = (k % 7 == 0 && i == k % 6) ? 0.0 : u(rng);
    const bool fast = t.admissible(v.data());
    ASSERT_EQ(fast, t.violation(v).empty()) << v.transpose();
    admissible += fast;
  }
  EXPECT_GT(admissible, 100);  // both outcomes were exercised
  EXPECT_LT(admissible, 19000);
}

TEST(ParameterTable, RefusesInconsistentEntries) {
  EXPECT_THROW(ParameterTable({{"a", "", 1.0, positive(), ""}, {"a", "", 1.0, positive(), ""}}),
               std::invalid_argument);
  EXPECT_THROW(ParameterTable({{"a", "", -1.0, positive(), ""}}), std::invalid_argument);
  EXPECT_THROW(ParameterTable({{"a", "", 1.0, withinSumOf({"b"}), ""}}), std::invalid_argument);
  EXPECT_EQ(smallTable().domainText(3), "[0, length + width]");
  EXPECT_EQ(smallTable().domainText(5), "any");
}

// Writing 1..n into the typed view and back gives 1..n: every table entry is
// bound to its own field, in table order.
TEST(ModelDescription, TypedViewsFollowTheTables) {
  const int n = rollPlaneDescription().parameters().size();
  const Eigen::VectorXd ramp = Eigen::VectorXd::LinSpaced(n, 1.0, n);
  EXPECT_EQ(VehicleParameters::fromVector(ramp, VehicleParameters()).toVector(), ramp);
  EXPECT_EQ(VehicleParameters().toVector(), rollPlaneDescription().parameters().defaults());
  EXPECT_EQ(VehicleParameters().bar_mass, 580.0);  // paper Table I
  EXPECT_EQ(VehicleParameters().added_mass_position, 0.762);
  const int m = fullCarDescription().parameters().size();
  const Eigen::VectorXd ramp4 = Eigen::VectorXd::LinSpaced(m, 1.0, m);
  EXPECT_EQ(FullCarParameters::fromVector(ramp4, FullCarParameters()).toVector(), ramp4);
  EXPECT_EQ(FullCarParameters().toVector(), fullCarDescription().parameters().defaults());
  EXPECT_EQ(FullCarParameters().wheelbase(), 2.6);
}

// A config with `yaml` and one uncertain parameter (both models have it).
std::string withUncertain(const std::string& yaml) {
  return yaml + "uncertain:\n  - {name: added_mass, nominal: 200.0, relative_range: 0.5}\n";
}

TEST(ModelDescription, TypeAndModelShareOneDescription) {
  EstimatorConfig c = parseConfigString(withUncertain("model: {type: full_car}\n"), "fc.yaml");
  EXPECT_EQ(&c.model_type->description(), &fullCarDescription());
  EXPECT_EQ(c.model->values, fullCarDescription().parameters().defaults());
  const EstimatorConfig r = parseConfigString(withUncertain(""), "rp.yaml");
  EXPECT_EQ(&r.model_type->description(), &rollPlaneDescription());
  // The default selection: the suspension channels (IMU channels by name).
  EXPECT_EQ(r.measurement.channels, rollPlaneDescription().defaultChannelNames());
  const auto& s = rollPlaneDescription().suspensions();
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[1].position_channel, 1);  // u2
  EXPECT_EQ(s[1].velocity_channel, 3);  // v2
}

std::string errorOf(const std::string& yaml) {
  try {
    parseConfigString(withUncertain(yaml), "bad.yaml");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

// The YAML bounds are the table's, including bounds set by another entry
// (its configured value).
TEST(ModelDescription, YamlReadingAppliesTheTableDomains) {
  const EstimatorConfig wide = parseConfigString(
      withUncertain("vehicle: {bar_length: 2.5, added_mass_position: 2.0}\n"), "ok.yaml");
  EXPECT_EQ(VehicleParameters::from(*wide.model).added_mass_position, 2.0);
  const std::string e = errorOf("vehicle: {added_mass_position: 2.0}\n");
  EXPECT_NE(e.find("vehicle.added_mass_position"), std::string::npos) << e;
  EXPECT_NE(e.find("1.524"), std::string::npos) << e;
  const std::string fc = errorOf("model: {type: full_car}\nvehicle: {added_mass_x: 2.7}\n");
  EXPECT_NE(fc.find("vehicle.added_mass_x"), std::string::npos) << fc;
  EXPECT_NE(fc.find("2.6"), std::string::npos) << fc;
  EXPECT_NE(errorOf("vehicle: {damper: cubic}\n").find("tanh or linear"), std::string::npos);
  EXPECT_NE(errorOf("vehicle: {damper_tanh_rate: 0}\n").find("vehicle.damper_tanh_rate"),
            std::string::npos);
}

// docs/models.md carries each built-in model's generated tables verbatim.
TEST(ModelDescription, DocsCarryTheGeneratedTables) {
  std::ifstream in(std::string(PC_EKF_SOURCE_DIR) + "/docs/models.md");
  ASSERT_TRUE(in) << "docs/models.md missing";
  std::stringstream text;
  text << in.rdbuf();
  for (const ModelDescription* d : {&rollPlaneDescription(), &fullCarDescription()}) {
    EXPECT_NE(text.str().find(d->markdown()), std::string::npos)
        << "docs/models.md is out of date for " << d->name()
        << "; regenerate with `model_tables` (expected):\n"
        << d->markdown();
  }
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
