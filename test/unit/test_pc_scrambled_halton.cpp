// Owen-scrambled Halton points (src/pc/scrambled_halton.h) and the design
// measure that chooses them (maxCoordinateCorrelation, defaultPointSequence).
#include <gtest/gtest.h>

#include <vector>

#include "pc_ekf/pc/collocation_design.h"
#include "pc_ekf/pc/point_sets.h"
#include "pc_ekf/pc/scrambled_halton.h"

namespace pc_ekf {
namespace {

TEST(ScrambledHalton, StrictlyInsideTheCubeAndReproducible) {
  const Eigen::MatrixXd a = scrambledHaltonPoints(200, 15, 7);
  EXPECT_TRUE((a.array() > 0.0).all() && (a.array() < 1.0).all());
  EXPECT_EQ(a, scrambledHaltonPoints(200, 15, 7));
  EXPECT_NE(a, scrambledHaltonPoints(200, 15, 8));
  // Nested like Halton, and a start index skips points.
  EXPECT_EQ(Eigen::MatrixXd(a.topRows(50)), scrambledHaltonPoints(50, 15, 7));
  EXPECT_EQ(Eigen::MatrixXd(a.middleRows(3, 20)), scrambledHaltonPoints(20, 15, 7, 4));
}

// Owen scrambling keeps the radical inverse's stratification: indices
// 0 .. b^2 - 1 put exactly one point in each interval [j / b^2, (j + 1) / b^2),
// in every coordinate.
TEST(ScrambledHalton, KeepsEachCoordinateStratified) {
  const std::vector<int> primes = firstPrimes(6);
  for (int d = 0; d < 6; ++d) {
    const int b = primes[d], cells = b * b;
    std::vector<int> count(cells, 0);
    for (int i = 0; i < cells; ++i) {
      const double x = scrambledRadicalInverse(i, b, d, 3);
      ++count[static_cast<int>(x * cells)];
    }
    for (int j = 0; j < cells; ++j) EXPECT_EQ(count[j], 1) << "base " << b << " cell " << j;
  }
}

// Scrambling permutes digits, so the values are not Halton's: the first point
// in base 2 is 0.5 unscrambled and uniformly placed over seeds when scrambled.
TEST(ScrambledHalton, FirstDigitIsUniformOverSeeds) {
  int upper = 0;
  const int seeds = 2000;
  for (int s = 0; s < seeds; ++s) upper += scrambledRadicalInverse(1, 2, 0, s) >= 0.5;
  // Binomial(2000, 1/2): std 22.4; 5 std.
  EXPECT_NEAR(upper, seeds / 2, 112);
}

TEST(ScrambledHalton, CorrelationKnownAnswers) {
  Eigen::MatrixXd p(4, 3);
  p << 0, 0, 1, 1, 2, 0, 2, 4, 1, 3, 6, 0;  // column 1 = 2 column 0; column 2 uncorrelated
  EXPECT_NEAR(maxCoordinateCorrelation(p), 1.0, 1e-12);
  p.col(1) = -p.col(1);
  EXPECT_NEAR(maxCoordinateCorrelation(p), 1.0, 1e-12);
  Eigen::MatrixXd q(4, 2);
  q << 0, 0, 0, 1, 1, 0, 1, 1;  // a 2 x 2 grid
  EXPECT_NEAR(maxCoordinateCorrelation(q), 0.0, 1e-15);
}

// vehicle_live.yaml's design (n = 15, Q = 306): plain Halton's coordinates
// correlate up to 0.186 (bases 31 and 37 ...), the scrambled design's (seed 1)
// up to 0.107; i.i.d. uniform points give about 0.15 at this size. At n = 18,
// Q = 380, Halton reaches 0.44.
TEST(ScrambledHalton, RemovesHaltonsCorrelationsAtTheShippedDimension) {
  EXPECT_NEAR(maxCoordinateCorrelation(haltonPoints(306, 15)), 0.186, 0.001);
  EXPECT_LT(maxCoordinateCorrelation(scrambledHaltonPoints(306, 15, 1)), 0.11);
  EXPECT_GT(maxCoordinateCorrelation(haltonPoints(380, 18)), 0.44);
  for (int seed = 1; seed <= 5; ++seed) {
    EXPECT_LT(maxCoordinateCorrelation(scrambledHaltonPoints(380, 18, seed)), 0.2) << seed;
  }
}

TEST(ScrambledHalton, DefaultSequenceAndDesign) {
  EXPECT_EQ(defaultPointSequence(2), PointSequence::kHalton);
  EXPECT_EQ(defaultPointSequence(kPlainHaltonMaxDimension), PointSequence::kHalton);
  EXPECT_EQ(defaultPointSequence(kPlainHaltonMaxDimension + 1), PointSequence::kScrambledHalton);
  // auto's tensor Gauss rule: order + 1 nodes per germ while (order + 1)^n <= Q.
  EXPECT_EQ(autoGaussNodes(2, 4, 30), 5);   // 25
  EXPECT_EQ(autoGaussNodes(2, 4, 24), 0);   // 25 > 24
  EXPECT_EQ(autoGaussNodes(2, 5, 30), 0);   // 36
  EXPECT_EQ(autoGaussNodes(1, 4, 30), 5);
  EXPECT_EQ(autoGaussNodes(3, 2, 30), 3);   // 27
  EXPECT_EQ(autoGaussNodes(3, 3, 30), 0);   // 64
  EXPECT_EQ(autoGaussNodes(5, 1, 30), 0);   // 32
  EXPECT_EQ(autoGaussNodes(40, 2, 30), 0);  // 3^40: no overflow
  EXPECT_EQ(pointSequenceFromString("scrambled_halton"), PointSequence::kScrambledHalton);
  EXPECT_EQ(toString(PointSequence::kScrambledHalton), "scrambled_halton");

  const PolynomialBasis basis(std::vector<GermSpec>(4, GermSpec{}), 2);
  const CollocationDesign a(basis, PointSequence::kScrambledHalton, 40, 1, 1e8,
                            ProjectionMethod::kAuto, false, 5);
  const CollocationDesign b(basis, PointSequence::kScrambledHalton, 40, 1, 1e8,
                            ProjectionMethod::kAuto, false, 6);
  EXPECT_EQ(a.projection(), ProjectionMethod::kRegression);
  EXPECT_EQ(a.pointCount(), 40);
  EXPECT_NE(a.points(), b.points());
  // The germ points are the Beta(2, 2) images of the unit-cube points.
  EXPECT_TRUE((a.points().array() > -1.0).all() && (a.points().array() < 1.0).all());
  // A quadratic in the germs is reproduced exactly by the order-2 fit.
  Eigen::MatrixXd values(1, 40);
  for (int q = 0; q < 40; ++q) {
    const Eigen::VectorXd x = a.points().row(q).transpose();
    values(0, q) = 1.0 + x(0) - 2.0 * x(1) * x(2) + 0.5 * x(3) * x(3);
  }
  EXPECT_LT(a.leaveOneOutError(values)(0), 1e-10);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
