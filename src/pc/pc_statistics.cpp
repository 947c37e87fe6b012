#include "pc_ekf/pc/pc_statistics.h"

#include <algorithm>
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

Eigen::MatrixXd sampleGerms(const PolynomialBasis& basis, int draws, std::uint64_t seed) {
  if (draws < 0) throw std::invalid_argument("sampleGerms: negative number of draws");
  std::mt19937_64 rng(seed);
  Eigen::MatrixXd samples(draws, basis.dimension());
  for (int i = 0; i < draws; ++i) {
    for (int d = 0; d < basis.dimension(); ++d) {
      // 53 random bits, offset by half a unit: u is strictly inside (0, 1), and
      // unlike std::uniform_real_distribution the stream is the same on every
      // standard library.
      const double u = (static_cast<double>(rng() >> 11) + 0.5) * 0x1.0p-53;
      samples(i, d) = basis.family(d).inverseCdf(u);
    }
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
