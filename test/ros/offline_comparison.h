// Shared by the rostests that replay a bag into estimator_node and compare
// every estimate with estimate_offline --bag's samples.csv (estimator_imu,
// estimator_road_free): mean, std and every PC coefficient to a relative
// tolerance.
#pragma once

#include <gtest/gtest.h>
#include <pc_ekf/ParameterEstimate.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

namespace pc_ekf::test {

inline ::testing::AssertionResult closeToOffline(double a, double b, double scale,
                                                 const std::string& what, double tolerance) {
  if (std::abs(a - b) <= tolerance * std::abs(scale)) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << what << ": node " << a << " vs offline " << b;
}

// `offline`: samples.csv's rows, `column`: its header's columns by name.
inline void compareWithOffline(const std::vector<ParameterEstimate>& estimates,
                               const std::vector<std::vector<double>>& offline,
                               const std::map<std::string, std::size_t>& column,
                               double tolerance) {
  ASSERT_EQ(estimates.size(), offline.size());
  double max_relative = 0.0;
  const auto close = [tolerance](double a, double b, double scale, const std::string& what) {
    return closeToOffline(a, b, scale, what, tolerance);
  };
  for (std::size_t k = 0; k < offline.size(); ++k) {
    const ParameterEstimate& e = estimates[k];
    ASSERT_EQ(e.sample_index, k + 1);
    ASSERT_TRUE(close(e.time, offline[k].at(column.at("t")), 1.0, "t"));
    for (std::size_t i = 0; i < e.names.size(); ++i) {
      const std::string& p = e.names[i];
      const double mean = offline[k].at(column.at(p + "_mean"));
      const std::string at = "sample " + std::to_string(k + 1) + " " + p;
      ASSERT_TRUE(close(e.mean[i], mean, mean, at + " mean"));
      const double sd = offline[k].at(column.at(p + "_stddev"));
      ASSERT_TRUE(close(e.stddev[i], sd, sd, at + " stddev"));
      max_relative = std::max(max_relative, std::abs(e.stddev[i] - sd) / sd);
      for (std::size_t j = 0; j < e.term_count; ++j) {
        ASSERT_TRUE(close(e.coefficients[i * e.term_count + j],
                          offline[k].at(column.at(p + "_c" + std::to_string(j))), mean,
                          at + " c" + std::to_string(j)));
      }
    }
  }
  ::testing::Test::RecordProperty("max_relative_stddev_difference", std::to_string(max_relative));
}

}  // namespace pc_ekf::test
