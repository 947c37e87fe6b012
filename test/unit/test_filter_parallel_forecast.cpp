// The forecast on several threads equals the one-thread forecast bit for bit
// (each collocation point is integrated independently of the others, and the
// sums over points are taken per fixed block, blocks added in order).
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

bool bitwiseEqual(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
}

// Filter states after every sample of the first 0.6 s (the bump) with
// `threads`; the leave-one-out errors of the forecasts in *loo.
std::vector<Eigen::MatrixXd> run(EstimatorConfig c, int threads, int* used_threads,
                                 std::vector<Eigen::VectorXd>* loo) {
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
    loo->push_back(r.forecast.loo_error);
  }
  return states;
}

void expectThreadCountInvariant(const EstimatorConfig& c) {
  int one = 0;
  std::vector<Eigen::VectorXd> reference_loo;
  const std::vector<Eigen::MatrixXd> reference = run(c, 1, &one, &reference_loo);
  ASSERT_EQ(one, 1);
  for (int threads : {2, 3}) {
    int used = 0;
    std::vector<Eigen::VectorXd> loo;
    const std::vector<Eigen::MatrixXd> states = run(c, threads, &used, &loo);
    EXPECT_EQ(used, threads);
    ASSERT_EQ(states.size(), 20u);
    ASSERT_EQ(states.size(), reference.size());
    for (std::size_t k = 0; k < states.size(); ++k) {
      EXPECT_TRUE(bitwiseEqual(states[k], reference[k]))
          << threads << " threads, sample " << k + 1 << ": max difference "
          << (states[k] - reference[k]).cwiseAbs().maxCoeff();
      EXPECT_TRUE(bitwiseEqual(loo[k], reference_loo[k]))
          << threads << " threads, sample " << k + 1;
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

// The blocked sums equal the direct products: X A^T, integration, Y P^T and
// CollocationDesign::leaveOneOutError of H Y, to rounding.
void expectBlockedForecastEqualsDirectProducts(EstimatorConfig c) {
  c.collocation.threads = 2;
  const auto model = makeModel(c, makeRoad(c));
  const auto propagator = makePropagator(c, model);
  ASSERT_GE(propagator->design().pointCount(), PcPropagator::kBlockedPoints);
  const int ns = propagator->stateCount(), np = propagator->parameterCount();
  Eigen::MatrixXd x = propagator->priorState();
  // Start off rest so that every channel varies over the points.
  x.topRows(ns).col(0).setConstant(0.01);
  x.topRows(ns).col(1).setConstant(0.002);
  const CollocationDesign& design = propagator->design();
  const Eigen::MatrixXd params = propagator->parametersAtPoints(x.bottomRows(np), nullptr);
  Eigen::ArrayXXd y = (x.topRows(ns) * design.designMatrix().transpose()).array();
  integrate(*model, *model->prepare(params), 0.0, 0.05, y, propagator->integration());
  const Eigen::MatrixXd expected = y.matrix() * design.projector().transpose();
  const Eigen::VectorXd expected_loo =
      design.leaveOneOutError(model->observationMatrix().topRows(4) * y.matrix());  // u1 .. v2

  const ForecastReport r = propagator->forecast(x, 0.0, 0.05);
  ASSERT_TRUE(r.ok);
  EXPECT_LE((x.topRows(ns) - expected).cwiseAbs().maxCoeff(),
            1e-12 * expected.cwiseAbs().maxCoeff());
  ASSERT_EQ(r.loo_error.size(), expected_loo.size());
  EXPECT_GT(expected_loo.minCoeff(), 0.0);
  EXPECT_LE((r.loo_error - expected_loo).cwiseAbs().maxCoeff(), 1e-10 * expected_loo.maxCoeff());
}

TEST(ParallelForecast, BlockedForecastEqualsDirectProducts) {
  // Regression (the projector is A's pseudo-inverse).
  EstimatorConfig c = withUncertain(loadConfigFile(kConfig),
                                    {"spring_linear_left", "spring_linear_right"}, 0.1, 0.1);
  c.collocation.points = 141;
  expectBlockedForecastEqualsDirectProducts(c);
  // Quadrature projection (7 x 7 Gauss nodes): the leave-one-out fit sums
  // over the points itself.
  c = loadConfigFile(kConfig);
  c.collocation.sequence = PointSequence::kGauss;
  c.collocation.points = 7;
  expectBlockedForecastEqualsDirectProducts(c);
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
