#include "pc_ekf/pc/pc_statistics.h"

#include <algorithm>
#include <cstring>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

namespace pc_ekf {
namespace {

void requireMeanColumn(const Eigen::MatrixXd& coefficients) {
  if (coefficients.cols() < 1) {
    throw std::invalid_argument("PC statistics: coefficient matrix has no columns");
  }
}

}  // namespace

Eigen::VectorXd pcMean(const Eigen::MatrixXd& coefficients) {
  requireMeanColumn(coefficients);
  return coefficients.col(0);
}

Eigen::MatrixXd pcCovariance(const Eigen::MatrixXd& coefficients) {
  requireMeanColumn(coefficients);
  const auto higher = coefficients.rightCols(coefficients.cols() - 1);
  return higher * higher.transpose();
}

Eigen::VectorXd pcStddev(const Eigen::MatrixXd& coefficients) {
  requireMeanColumn(coefficients);
  return coefficients.rightCols(coefficients.cols() - 1).rowwise().norm();
}

Eigen::VectorXd Histogram::centres() const {
  const Eigen::Index bins = densities.size();
  return 0.5 * (edges.head(bins) + edges.tail(bins));
}

int gemvBlockColumns(Eigen::Index rows, Eigen::Index terms) {
  if (terms < 128) return static_cast<int>(terms);
  return rows * static_cast<Eigen::Index>(sizeof(double)) < 32000 ? 16 : 4;
}

double gemvValue(const double* psi_row, Eigen::Index stride, const double* c, Eigen::Index terms,
                 int block_cols) {
  double value = 0.0;
  for (Eigen::Index j2 = 0; j2 < terms; j2 += block_cols) {
    const Eigen::Index end = std::min<Eigen::Index>(j2 + block_cols, terms);
    double block = 0.0;
    for (Eigen::Index j = j2; j < end; ++j) block += psi_row[j * stride] * c[j];
    value += block;
  }
  return value;
}

namespace {
constexpr int kLanes = 16;  // draws accumulated in registers at once
}  // namespace

// out[b] = sum_j psi[j][b] c[j] for `count` draws, summed as
// Eigen's column-major matrix-vector product sums pcHistogram's
// `basis.evaluate(germs) * coefficients`: per draw from zero, term after term
// within blocks of `block_cols` terms, the block sums added to the running
// result (one block when S < 128). No fused multiply-add in either (a plain
// x86-64 build), so the bits agree.
// GCC vector extensions: one AVX2 register per four draws where the CPU has
// it (the "avx2" clone), two SSE2 registers otherwise; same bits either way.
typedef double Lanes4 __attribute__((vector_size(32)));
#if defined(__x86_64__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
void gemvOrderValues(const double* const* psi, const double* c, int terms, int block_cols,
                     int count, double* out) {
  // Named accumulators (not arrays): GCC keeps them in registers.
  for (int b0 = 0; b0 < count; b0 += kLanes) {
    Lanes4 r0 = {}, r1 = {}, r2 = {}, r3 = {};
    for (int j2 = 0; j2 < terms; j2 += block_cols) {
      const int jend = std::min(j2 + block_cols, terms);
      Lanes4 a0 = {}, a1 = {}, a2 = {}, a3 = {};
      for (int j = j2; j < jend; ++j) {
        const Lanes4 cj = {c[j], c[j], c[j], c[j]};
        const double* p = psi[j] + b0;
        Lanes4 p0, p1, p2, p3;
        std::memcpy(&p0, p, sizeof p0);
        std::memcpy(&p1, p + 4, sizeof p1);
        std::memcpy(&p2, p + 8, sizeof p2);
        std::memcpy(&p3, p + 12, sizeof p3);
        a0 += p0 * cj;
        a1 += p1 * cj;
        a2 += p2 * cj;
        a3 += p3 * cj;
      }
      r0 += a0;
      r1 += a1;
      r2 += a2;
      r3 += a3;
    }
    double res[kLanes];
    std::memcpy(res, &r0, sizeof r0);
    std::memcpy(res + 4, &r1, sizeof r1);
    std::memcpy(res + 8, &r2, sizeof r2);
    std::memcpy(res + 12, &r3, sizeof r3);
    std::memcpy(out + b0, res,
                static_cast<std::size_t>(std::min(kLanes, count - b0)) * sizeof(double));
  }
}

Eigen::MatrixXd sampleGerms(const PolynomialBasis& basis, int draws, std::uint64_t seed) {
  if (draws < 0) throw std::invalid_argument("sampleGerms: negative number of draws");
  GermGenerator rng(seed);
  Eigen::MatrixXd samples(draws, basis.dimension());
  for (int i = 0; i < draws; ++i) {
    for (int d = 0; d < basis.dimension(); ++d) samples(i, d) = drawGerm(rng, basis.family(d));
  }
  return samples;
}

Histogram pcHistogram(const PolynomialBasis& basis, const Eigen::VectorXd& coefficients, int draws,
                      int bins, std::uint64_t seed, double lo, double hi, double* outside_mass) {
  if (coefficients.size() != basis.size()) {
    throw std::invalid_argument("pcHistogram: " + std::to_string(coefficients.size()) +
                                " coefficients for a basis of " + std::to_string(basis.size()));
  }
  if (draws < 1 || bins < 1) throw std::invalid_argument("pcHistogram: need draws, bins >= 1");
  const Eigen::VectorXd values = basis.evaluate(sampleGerms(basis, draws, seed)) * coefficients;
  if (!(lo < hi)) {
    lo = values.minCoeff();
    hi = values.maxCoeff();
    if (!(lo < hi)) {  // a constant expansion: give its single value a unit-width bin
      lo -= 0.5;
      hi += 0.5;
    }
  }
  const double width = (hi - lo) / bins;
  Eigen::VectorXd counts = Eigen::VectorXd::Zero(bins);
  int outside = 0;
  for (Eigen::Index i = 0; i < values.size(); ++i) {
    const double v = values(i);
    if (!(v >= lo && v <= hi)) {
      ++outside;
      continue;
    }
    const int bin = std::min(bins - 1, static_cast<int>((v - lo) / width));
    counts(bin) += 1.0;
  }
  Histogram h;
  h.edges = Eigen::VectorXd::LinSpaced(bins + 1, lo, hi);
  // Dividing by all draws (not only those in range) makes the area equal the
  // in-range probability, so a clipped range shows up as missing area.
  h.densities = counts / (static_cast<double>(draws) * width);
  if (outside_mass != nullptr) *outside_mass = static_cast<double>(outside) / draws;
  return h;
}

}  // namespace pc_ekf
