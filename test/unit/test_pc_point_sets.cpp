// Halton / Hammersley point sets and their map to the germs (docs/method.md §3.4).
#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

#include "pc_ekf/pc/orthonormal_family.h"
#include "pc_ekf/pc/point_sets.h"

namespace pc_ekf {
namespace {

TEST(PointSets, RadicalInverseValues) {
  const double base2[] = {0.5, 0.25, 0.75, 0.125, 0.625, 0.375, 0.875, 0.0625};
  const double base3[] = {1 / 3.0, 2 / 3.0, 1 / 9.0, 4 / 9.0, 7 / 9.0, 2 / 9.0, 5 / 9.0, 8 / 9.0};
  for (int i = 0; i < 8; ++i) {
    EXPECT_DOUBLE_EQ(radicalInverse(i + 1, 2), base2[i]) << i + 1;
    EXPECT_DOUBLE_EQ(radicalInverse(i + 1, 3), base3[i]) << i + 1;
  }
  EXPECT_DOUBLE_EQ(radicalInverse(0, 5), 0.0);
  EXPECT_DOUBLE_EQ(radicalInverse(7, 5), 11 / 25.0);  // 7 = "12" in base 5 -> 0.21 = 2/5 + 1/25
  EXPECT_THROW(radicalInverse(3, 1), std::invalid_argument);
}

TEST(PointSets, FirstPrimes) {
  EXPECT_EQ(firstPrimes(8), (std::vector<int>{2, 3, 5, 7, 11, 13, 17, 19}));
  EXPECT_TRUE(firstPrimes(0).empty());
}

TEST(PointSets, HaltonFirstPointsAndNesting) {
  const Eigen::MatrixXd h = haltonPoints(30, 3);
  ASSERT_EQ(h.rows(), 30);
  ASSERT_EQ(h.cols(), 3);
  EXPECT_DOUBLE_EQ(h(0, 0), 0.5);
  EXPECT_DOUBLE_EQ(h(0, 1), 1 / 3.0);
  EXPECT_DOUBLE_EQ(h(0, 2), 0.2);
  EXPECT_DOUBLE_EQ(h(1, 0), 0.25);
  EXPECT_DOUBLE_EQ(h(1, 1), 2 / 3.0);
  EXPECT_DOUBLE_EQ(h(2, 0), 0.75);
  EXPECT_DOUBLE_EQ(h(2, 1), 1 / 9.0);
  EXPECT_DOUBLE_EQ(h(3, 0), 0.125);
  EXPECT_DOUBLE_EQ(h(3, 1), 4 / 9.0);
  EXPECT_TRUE((h.array() > 0.0).all() && (h.array() < 1.0).all());
  // Nesting: the first Q points do not change when Q grows (why the paper prefers Halton).
  EXPECT_EQ(Eigen::MatrixXd(h.topRows(10)), haltonPoints(10, 3));
  // A start index skips the first points.
  EXPECT_EQ(haltonPoints(5, 3, 4), Eigen::MatrixXd(h.middleRows(3, 5)));
  EXPECT_THROW(haltonPoints(5, 2, 0), std::invalid_argument);
}

TEST(PointSets, HammersleyCoordinates) {
  const Eigen::MatrixXd h = hammersleyPoints(4, 3);
  const double first[] = {0.125, 0.375, 0.625, 0.875};          // (i - 1/2)/Q
  const double second[] = {0.5, 0.25, 0.75, 0.125};             // base 2
  const double third[] = {1 / 3.0, 2 / 3.0, 1 / 9.0, 4 / 9.0};  // base 3
  for (int i = 0; i < 4; ++i) {
    EXPECT_DOUBLE_EQ(h(i, 0), first[i]);
    EXPECT_DOUBLE_EQ(h(i, 1), second[i]);
    EXPECT_DOUBLE_EQ(h(i, 2), third[i]);
  }
}

TEST(PointSets, MapToGermsUsesEachInverseCdf) {
  const GermSpec beta22{GermFamily::kBeta, 2, 2};
  const GermSpec gauss{GermFamily::kGaussian, 0, 0};
  Eigen::MatrixXd u(2, 2);
  u << 0.5, 0.975, 0.104, 0.5;
  const Eigen::MatrixXd xi = mapToGerms(u, {beta22, gauss});
  EXPECT_NEAR(xi(0, 0), 0.0, 1e-15);
  EXPECT_NEAR(xi(0, 1), 1.959963984540054, 1e-14);
  EXPECT_NEAR(xi(1, 0), -0.6, 1e-14);
  EXPECT_NEAR(xi(1, 1), 0.0, 1e-15);
  EXPECT_THROW(mapToGerms(u, {beta22}), std::invalid_argument);
  u(0, 0) = 1.0;  // on the boundary: no finite preimage
  EXPECT_THROW(mapToGerms(u, {beta22, gauss}), std::invalid_argument);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
