// ParameterPdfSampler against the algorithm it replaces, computed here from
// scratch: the germ draws, the dense basis matrix at the draws
// (PolynomialBasis::evaluate, one row per draw), its product with each
// parameter's coefficients and the binning over the sample range. The
// histograms must agree bit for bit at the same draws.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "pc_ekf/pc/in_parts.h"
#include "pc_ekf/pc/pc_statistics.h"
#include "pc_ekf/pc/pdf_sampler.h"

namespace pc_ekf {
namespace {

const GermSpec kBeta22{GermFamily::kBeta, 2.0, 2.0};

// The old route, written out: dense draws x S basis, product, binning.
Histogram referenceHistogram(const Eigen::MatrixXd& psi, const Eigen::VectorXd& c, int bins) {
  const Eigen::VectorXd values = psi * c;
  double lo = values.minCoeff(), hi = values.maxCoeff();
  if (!(lo < hi)) {
    lo -= 0.5;
    hi += 0.5;
  }
  const double width = (hi - lo) / bins;
  Eigen::VectorXd counts = Eigen::VectorXd::Zero(bins);
  for (Eigen::Index i = 0; i < values.size(); ++i) {
    counts(std::min(bins - 1, static_cast<int>((values(i) - lo) / width))) += 1.0;
  }
  Histogram h;
  h.edges = Eigen::VectorXd::LinSpaced(bins + 1, lo, hi);
  h.densities = counts / (static_cast<double>(values.size()) * width);
  return h;
}

// A filter-like posterior: means, then a spread over every term (the Kalman
// update mixes all germs into every parameter).
Eigen::MatrixXd posteriorLike(int parameters, int terms, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd c(parameters, terms);
  for (int i = 0; i < parameters; ++i) {
    c(i, 0) = 10.0 * (i + 1);
    for (int j = 1; j < terms; ++j) c(i, j) = normal(rng) / j;
  }
  return c;
}

void expectSameHistograms(const PolynomialBasis& basis, const Eigen::MatrixXd& c, int draws,
                          int bins, std::uint64_t seed) {
  const ParameterPdfSampler sampler(basis, draws, bins, seed);
  const std::vector<Histogram> fast = sampler.histograms(c);
  ASSERT_EQ(fast.size(), static_cast<std::size_t>(c.rows()));
  const Eigen::MatrixXd psi = basis.evaluate(sampleGerms(basis, draws, seed));
  for (Eigen::Index i = 0; i < c.rows(); ++i) {
    const Histogram ref = referenceHistogram(psi, c.row(i).transpose(), bins);
    ASSERT_EQ(fast[i].edges.size(), bins + 1);
    ASSERT_EQ(fast[i].densities.size(), bins);
    for (int b = 0; b <= bins; ++b) EXPECT_EQ(fast[i].edges(b), ref.edges(b)) << i << " edge " << b;
    for (int b = 0; b < bins; ++b) {
      EXPECT_EQ(fast[i].densities(b), ref.densities(b)) << i << " bin " << b;
    }
    // And pcHistogram (estimate_offline's old per-parameter call) at the same seed.
    const Histogram old = pcHistogram(basis, c.row(i).transpose(), draws, bins, seed);
    EXPECT_EQ(fast[i].edges, old.edges) << i;
    EXPECT_EQ(fast[i].densities, old.densities) << i;
  }
}

TEST(PdfSampler, RollPlaneTolerancesN11EqualsTheDenseRouteBitForBit) {
  // n = 11, p = 2: S = 78 terms, the benchmark configuration's basis.
  const PolynomialBasis basis(std::vector<GermSpec>(11, kBeta22), 2);
  ASSERT_EQ(basis.size(), 78);
  expectSameHistograms(basis, posteriorLike(11, 78, 1), 20000, 60, 11);
}

TEST(PdfSampler, PaperBasisAndMixedFamiliesEqualTheDenseRoute) {
  expectSameHistograms(PolynomialBasis({kBeta22, kBeta22}, 4), posteriorLike(2, 15, 2), 100000, 60,
                       11);
  const PolynomialBasis mixed(
      {GermSpec{GermFamily::kUniform, 0, 0}, GermSpec{GermFamily::kGaussian, 0, 0},
       GermSpec{GermFamily::kGamma, 3.0, 0}, GermSpec{GermFamily::kBeta, 2.0, 5.0}},
      4);
  // A draw count that is not a multiple of the sampler's blocks.
  expectSameHistograms(mixed, posteriorLike(3, mixed.size(), 3), 3001, 17, 5);
}

TEST(PdfSampler, ManyTermsFollowTheBlockedSummationOfTheDenseProduct) {
  // S = 165 >= 128: the dense product sums in blocks of terms whose size
  // depends on the draws (16 below 4000 draws, 4 above).
  const PolynomialBasis basis(std::vector<GermSpec>(8, kBeta22), 3);
  ASSERT_EQ(basis.size(), 165);
  expectSameHistograms(basis, posteriorLike(2, 165, 4), 3000, 40, 1);
  expectSameHistograms(basis, posteriorLike(2, 165, 5), 4100, 40, 2);
}

// pdf.shared_draws: false (the paper configs): parameter i draws with seed + i,
// as estimate_offline's pcHistogram calls did, bit for bit.
TEST(PdfSampler, IndependentDrawsPerParameterEqualPcHistogramAtSeedPlusI) {
  const PolynomialBasis basis({kBeta22, kBeta22}, 4);
  const Eigen::MatrixXd c = posteriorLike(2, basis.size(), 6);
  const ParameterPdfSampler sampler(basis, 50000, 60, 11, 2);
  const std::vector<Histogram> h = sampler.histograms(c);
  ASSERT_EQ(h.size(), 2u);
  for (int i = 0; i < 2; ++i) {
    const Histogram old = pcHistogram(basis, c.row(i).transpose(), 50000, 60, 11 + i);
    EXPECT_EQ(h[i].edges, old.edges) << i;
    EXPECT_EQ(h[i].densities, old.densities) << i;
  }
  // The second parameter's draws differ from the shared set's.
  const ParameterPdfSampler shared_sampler(basis, 50000, 60, 11);
  const std::vector<Histogram> shared = shared_sampler.histograms(c);
  EXPECT_EQ(shared[0].densities, h[0].densities);
  EXPECT_NE(shared[1].densities, h[1].densities);
  EXPECT_THROW(sampler.histograms(c.topRows(1)), std::invalid_argument);
  // Derived quantities (any number of rows) on the first seed's draws, as
  // pcHistogram(..., seed) of each: the set the sampler already drew.
  const Eigen::MatrixXd three = posteriorLike(3, basis.size(), 8);
  for (const ParameterPdfSampler* s : {&sampler, &shared_sampler}) {
    const std::vector<Histogram> first = s->histogramsOnFirstDraws(three);
    ASSERT_EQ(first.size(), 3u);
    for (int i = 0; i < 3; ++i) {
      const Histogram old = pcHistogram(basis, three.row(i).transpose(), 50000, 60, 11);
      EXPECT_EQ(first[i].edges, old.edges) << i;
      EXPECT_EQ(first[i].densities, old.densities) << i;
    }
  }
}

// The set-up shared among threads (estimate_offline draws on every core):
// each thread's generator skips to its first draw, so any thread count gives
// the dense route's histograms, also when the draws end inside a chunk.
TEST(PdfSampler, SetUpOnSeveralThreadsGivesTheSameHistograms) {
  const PolynomialBasis basis(std::vector<GermSpec>(5, kBeta22), 2);
  const Eigen::MatrixXd c = posteriorLike(5, basis.size(), 7);
  const int draws = 5 * 1024 + 37;
  const Eigen::MatrixXd psi = basis.evaluate(sampleGerms(basis, draws, 3));
  for (int threads : {2, 3, 8}) {
    const std::vector<Histogram> h =
        ParameterPdfSampler(basis, draws, 30, 3, PdfSetupThreads{threads}).histograms(c, threads);
    ASSERT_EQ(h.size(), 5u);
    for (int i = 0; i < 5; ++i) {
      const Histogram ref = referenceHistogram(psi, c.row(i).transpose(), 30);
      EXPECT_EQ(h[i].edges, ref.edges) << threads << " threads, parameter " << i;
      EXPECT_EQ(h[i].densities, ref.densities) << threads << " threads, parameter " << i;
    }
  }
  // Independent draws per parameter, built on 2 threads: seed + i each.
  const std::vector<Histogram> independent =
      ParameterPdfSampler(basis, 2000, 30, 3, 5, PdfSetupThreads{2}).histograms(c);
  for (int i = 0; i < 5; ++i) {
    const Histogram old = pcHistogram(basis, c.row(i).transpose(), 2000, 30, 3 + i);
    EXPECT_EQ(independent[i].edges, old.edges) << i;
    EXPECT_EQ(independent[i].densities, old.densities) << i;
  }
  EXPECT_THROW(ParameterPdfSampler(basis, 0, 30, 3, 5, PdfSetupThreads{2}), std::invalid_argument);
}

// The threads' split (in_parts.h): every index once, and a part's exception
// reaches the caller after all parts have ended.
TEST(InParts, EveryIndexOnceAndAHelperPartsExceptionReachesTheCaller) {
  std::vector<int> seen(1000, 0);
  inNumberedParts(1000, 3, [&](int, int begin, int end) {
    for (int i = begin; i < end; ++i) ++seen[i];
  });
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), 1000);
  std::vector<int> ended(3, 0);
  EXPECT_THROW(inNumberedParts(30, 3,
                               [&](int part, int, int) {
                                 ended[part] = 1;
                                 if (part == 2) throw std::invalid_argument("part 2");
                               }),
               std::invalid_argument);
  EXPECT_EQ(ended, std::vector<int>({1, 1, 1}));
}

TEST(PdfSampler, ConstantExpansionGetsAUnitWidthBinAndUnitArea) {
  const PolynomialBasis basis({kBeta22, kBeta22}, 2);
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(1, basis.size());
  c(0, 0) = 3.0;
  const std::vector<Histogram> h = ParameterPdfSampler(basis, 1000, 4, 1).histograms(c);
  ASSERT_EQ(h.size(), 1u);
  EXPECT_EQ(h[0].edges(0), 2.5);
  EXPECT_EQ(h[0].edges(4), 3.5);
  EXPECT_DOUBLE_EQ((h[0].densities.array() * 0.25).sum(), 1.0);
}

TEST(PdfSampler, BadInputIsRefusedNamingTheProblem) {
  const PolynomialBasis basis({kBeta22, kBeta22}, 2);
  EXPECT_THROW(ParameterPdfSampler(basis, 0, 4, 1), std::invalid_argument);
  EXPECT_THROW(ParameterPdfSampler(basis, 10, 0, 1), std::invalid_argument);
  const ParameterPdfSampler sampler(basis, 100, 4, 1);
  try {
    sampler.histograms(Eigen::MatrixXd::Zero(2, 5));
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("basis of 6"), std::string::npos) << e.what();
  }
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(2, 6);
  c(1, 3) = std::nan("");
  EXPECT_TRUE(sampler.histograms(c).empty());
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
