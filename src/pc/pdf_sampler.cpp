#include "pc_ekf/pc/pdf_sampler.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <stdexcept>
#include <string>

namespace pc_ekf {
namespace {

constexpr int kBlock = 128;  // draws per block: the block's basis (S x 48, 30 KB at S = 78) stays in L1
constexpr int kLanes = 16;    // draws accumulated in registers at once
constexpr int kPad = kLanes;  // rows padded so that a block's last lanes stay inside

// out[r][b] = sum_j psi[j][b] * c(r, j) for the block's `count` draws (psi[j]
// points at term j's values in the block, out[r] at quantity r's), summed as
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
void accumulate(const double* const* psi, const double* c, int terms, int block_cols, int count,
                double* out) {
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

// out[b] = a[b] * b[b]: a product term's values (AVX2 where available).
#if defined(__x86_64__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
void multiply(const double* a, const double* b, int count, double* out) {
  for (int i = 0; i < count; ++i) out[i] = a[i] * b[i];
}

// pcHistogram's binning over the sample range (lo = hi = 0 there).
Histogram binned(const Eigen::Ref<const Eigen::VectorXd>& values, int bins) {
  double lo = values.minCoeff(), hi = values.maxCoeff();
  if (!(lo < hi)) {
    lo -= 0.5;
    hi += 0.5;
  }
  const double width = (hi - lo) / bins;
  std::vector<int> counts(static_cast<std::size_t>(bins), 0);
  for (Eigen::Index i = 0; i < values.size(); ++i) {
    const double v = values(i);
    if (!(v >= lo && v <= hi)) continue;
    ++counts[static_cast<std::size_t>(std::min(bins - 1, static_cast<int>((v - lo) / width)))];
  }
  Histogram h;
  h.edges = Eigen::VectorXd::LinSpaced(bins + 1, lo, hi);
  h.densities.resize(bins);
  for (int b = 0; b < bins; ++b) {
    h.densities(b) =
        counts[static_cast<std::size_t>(b)] / (static_cast<double>(values.size()) * width);
  }
  return h;
}

}  // namespace

ParameterPdfSampler::ParameterPdfSampler(const PolynomialBasis& basis, int draws, int bins,
                                         std::uint64_t seed)
    : terms_(basis.size()), draws_(draws), bins_(bins) {
  if (draws < 1 || bins < 1) {
    throw std::invalid_argument("ParameterPdfSampler: need draws, bins >= 1 (got " +
                                std::to_string(draws) + ", " + std::to_string(bins) + ")");
  }
  const int n = basis.dimension(), p = basis.order();
  const Eigen::MatrixXd germs = sampleGerms(basis, draws, seed);
  // OrthonormalFamily::evaluate's recurrence with its constants taken out of
  // the loop (same operations in the same order).
  // Rows padded by kPad zeros.
  const std::size_t stride = static_cast<std::size_t>(draws) + kPad;
  univariate_.assign(static_cast<std::size_t>(n) * p * stride, 0.0);
  for (int d = 0; d < n; ++d) {
    const OrthonormalFamily& f = basis.family(d);
    std::vector<double> a(p + 1), sb(p + 1);
    for (int k = 0; k < p; ++k) a[k] = f.recurrenceA(k);
    for (int k = 1; k <= p; ++k) sb[k] = std::sqrt(f.recurrenceB(k));
    for (int k = 1; k <= p; ++k) {
      double* row = univariate_.data() + (static_cast<std::size_t>(d) * p + k - 1) * stride;
      const double* prev = k >= 2 ? row - stride : nullptr;
      const double* prev2 = k >= 3 ? row - 2 * stride : nullptr;
      for (int q = 0; q < draws; ++q) {
        const double x = germs(q, d);
        if (k == 1) {
          row[q] = (x - a[0]) / sb[1];
        } else {
          const double before = k == 2 ? 1.0 : prev2[q];
          row[q] = ((x - a[k - 1]) * prev[q] - sb[k - 1] * before) / sb[k];
        }
      }
    }
  }
  for (const std::vector<int>& index : basis.multiIndices()) {
    std::vector<int> rows;
    for (int d = 0; d < n; ++d) {
      if (index[d] > 0) rows.push_back(d * p + index[d] - 1);
    }
    factors_.push_back(std::move(rows));
  }
}

ParameterPdfSampler::ParameterPdfSampler(const PolynomialBasis& basis, int draws, int bins,
                                         std::uint64_t seed, int parameters)
    : terms_(basis.size()), draws_(draws), bins_(bins) {
  for (int i = 0; i < parameters; ++i) per_parameter_.emplace_back(basis, draws, bins, seed + i);
}

std::vector<Histogram> ParameterPdfSampler::histograms(const Eigen::MatrixXd& coefficients) const {
  if (!per_parameter_.empty()) {
    if (coefficients.rows() != static_cast<Eigen::Index>(per_parameter_.size())) {
      throw std::invalid_argument("ParameterPdfSampler: " + std::to_string(coefficients.rows()) +
                                  " quantities for a sampler of " +
                                  std::to_string(per_parameter_.size()) + " independent draw sets");
    }
    std::vector<Histogram> out;
    for (std::size_t i = 0; i < per_parameter_.size(); ++i) {
      std::vector<Histogram> h = per_parameter_[i].histograms(coefficients.row(i));
      if (h.empty()) return {};
      out.push_back(std::move(h.front()));
    }
    return out;
  }
  if (coefficients.cols() != terms_) {
    throw std::invalid_argument("ParameterPdfSampler: " + std::to_string(coefficients.cols()) +
                                " coefficients per quantity for a basis of " +
                                std::to_string(terms_));
  }
  std::vector<Histogram> out;
  if (!coefficients.allFinite()) return out;
  const Eigen::Index quantities = coefficients.rows();
  // Eigen's block heuristic for pcHistogram's draws x S product (lhs stride = draws).
  const int block_cols = gemvBlockColumns(draws_, terms_);
  // Column per quantity, padded so that a block's last lanes stay inside.
  Eigen::MatrixXd values(draws_ + kPad, quantities);
  std::vector<double> products(static_cast<std::size_t>(terms_) * (kBlock + kPad), 1.0);
  std::vector<const double*> psi(static_cast<std::size_t>(terms_));
  // Coefficients row by row, contiguous.
  std::vector<double> rows(static_cast<std::size_t>(quantities) * terms_);
  for (Eigen::Index r = 0; r < quantities; ++r) {
    for (int j = 0; j < terms_; ++j) rows[r * terms_ + j] = coefficients(r, j);
  }
  for (int q0 = 0; q0 < draws_; q0 += kBlock) {
    const int count = std::min(kBlock, draws_ - q0);
    for (int j = 0; j < terms_; ++j) {
      const std::vector<int>& f = factors_[static_cast<std::size_t>(j)];
      double* row = products.data() + static_cast<std::size_t>(j) * (kBlock + kPad);
      if (f.size() == 1) {  // one factor: its values as they are
        psi[j] = univariate_.data() + static_cast<std::size_t>(f[0]) * (draws_ + kPad) + q0;
        continue;
      }
      psi[j] = row;
      if (f.empty()) continue;  // the constant term: stays 1
      const double* first =
          univariate_.data() + static_cast<std::size_t>(f[0]) * (draws_ + kPad) + q0;
      const double* second =
          univariate_.data() + static_cast<std::size_t>(f[1]) * (draws_ + kPad) + q0;
      multiply(first, second, count, row);
      for (std::size_t m = 2; m < f.size(); ++m) {
        multiply(row, univariate_.data() + static_cast<std::size_t>(f[m]) * (draws_ + kPad) + q0,
                 count, row);
      }
    }
    for (Eigen::Index r = 0; r < quantities; ++r) {
      accumulate(psi.data(), rows.data() + r * terms_, terms_, block_cols, count,
                 values.col(r).data() + q0);
    }
  }
  for (Eigen::Index r = 0; r < quantities; ++r)
    out.push_back(binned(values.col(r).head(draws_), bins_));
  return out;
}

}  // namespace pc_ekf
