// The forecast on several threads equals the one-thread forecast bit for bit
// (each collocation point is integrated independently of the others).
#include <gtest/gtest.h>

#include <cstring>

#include "pc_ekf/filter/column_workers.h"
#include "pc_ekf/filter/one_step_filter.h"
#include "pc_ekf/io/estimation_setup.h"

namespace pc_ekf {
namespace {

const std::string kConfig = std::string(PC_EKF_SOURCE_DIR) + "/config/speed_bump.yaml";

bool bitwiseEqual(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
}

// Filter states after every sample of the first 0.6 s (the bump) with `threads`.
std::vector<Eigen::MatrixXd> run(EstimatorConfig c, int threads, int* used_threads) {
  c.collocation.threads = threads;
  c.sampling.samples = 100;  // 0.03 s apart
  const auto model = makeModel(c, makeRoad(c));
  const auto propagator = makePropagator(c, model);
  *used_threads = propagator->threads();
  const MeasurementSeries data = synthesizeFromConfig(c, *model, 3);
  OneStepFilter filter(propagator, makeOneStepSettings(c));
  std::vector<Eigen::MatrixXd> states;
  for (std::size_t k = 0; k < 20 && k < data.size(); ++k) {
    const StepResult r = filter.process(data[k]);
    states.push_back(filter.state());
    EXPECT_EQ(r.forecast.loo_error.size(), 4);
  }
  return states;
}

void expectThreadCountInvariant(const EstimatorConfig& c) {
  int one = 0;
  const std::vector<Eigen::MatrixXd> reference = run(c, 1, &one);
  ASSERT_EQ(one, 1);
  for (int threads : {2, 3}) {
    int used = 0;
    const std::vector<Eigen::MatrixXd> states = run(c, threads, &used);
    EXPECT_EQ(used, threads);
    ASSERT_EQ(states.size(), 20u);
    ASSERT_EQ(states.size(), reference.size());
    for (std::size_t k = 0; k < states.size(); ++k) {
      EXPECT_TRUE(bitwiseEqual(states[k], reference[k]))
          << threads << " threads, sample " << k + 1 << ": max difference "
          << (states[k] - reference[k]).cwiseAbs().maxCoeff();
    }
  }
}

TEST(ParallelForecast, HaltonDesignBitwiseEqualToOneThread) {
  EstimatorConfig c = withUncertain(loadConfigFile(kConfig),
                                    {"spring_linear_left", "spring_linear_right"}, 0.1, 0.1);
  c.collocation.points = 141;  // not a multiple of the SIMD width or the thread count
  expectThreadCountInvariant(c);
}

TEST(ParallelForecast, SparseGridBitwiseEqualToOneThread) {
  EstimatorConfig c = withUncertain(
      loadConfigFile(kConfig),
      {"spring_linear_left", "spring_linear_right", "damping_left", "damping_right"}, 0.1, 0.1);
  c.pc_order = 2;
  c.collocation.sequence = PointSequence::kSmolyak;
  c.collocation.level = 2;
  expectThreadCountInvariant(c);
}

TEST(ParallelForecast, SmallDesignsStayOnOneThread) {
  // The paper's Q = 30: splitting would cost more than it saves.
  EstimatorConfig c = loadConfigFile(kConfig);
  c.collocation.threads = 2;
  EXPECT_EQ(makePropagator(c, makeModel(c, makeRoad(c)))->threads(), 1);
}

TEST(ColumnParts, AlignedBoundariesCoverTheColumns) {
  EXPECT_EQ(columnParts(141, 2, 24), (std::vector<long>{0, 64, 141}));
  EXPECT_EQ(columnParts(141, 3, 24), (std::vector<long>{0, 40, 88, 141}));
  EXPECT_EQ(columnParts(141, 4, 16), (std::vector<long>{0, 32, 64, 104, 141}));
  EXPECT_EQ(columnParts(30, 2, 24), (std::vector<long>{0, 30}));
  EXPECT_EQ(columnParts(0, 2, 24), (std::vector<long>{0, 0}));
}

TEST(ColumnWorkers, RunsEveryPartOnceAndRethrows) {
  ColumnWorkers workers(3);
  EXPECT_EQ(workers.threads(), 3);
  std::vector<int> hits(100, 0);
  const std::vector<long> bounds{0, 10, 50, 70, 100};  // more parts than threads
  for (int round = 0; round < 50; ++round) {
    workers.run(bounds, [&](int, long b, long e) {
      for (long i = b; i < e; ++i) ++hits[i];
    });
  }
  for (int h : hits) EXPECT_EQ(h, 50);
  EXPECT_THROW(workers.run(bounds,
                           [](int part, long, long) {
                             if (part == 2) throw std::runtime_error("part 2");
                           }),
               std::runtime_error);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
