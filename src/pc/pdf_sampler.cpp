#include "pc_ekf/pc/pdf_sampler.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>

#include "pc_ekf/pc/in_parts.h"

namespace pc_ekf {
namespace {

constexpr int kBlock = 32;  // draws per block: the block's basis (S x 32, 20 KB at S = 78) stays in L1
constexpr int kLanes = 16;    // draws accumulated in registers at once
constexpr int kPad = kLanes;  // rows padded so that a block's last lanes stay inside

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
                                         std::uint64_t seed, PdfSetupThreads threads)
    : terms_(basis.size()), draws_(draws), bins_(bins) {
  if (draws < 1 || bins < 1) {
    throw std::invalid_argument("ParameterPdfSampler: need draws, bins >= 1 (got " +
                                std::to_string(draws) + ", " + std::to_string(bins) + ")");
  }
  const int n = basis.dimension(), p = basis.order();
  // OrthonormalFamily::evaluate's recurrence with its constants taken out of
  // the loop (same operations in the same order), on the germ values of
  // sampleGerms's stream (drawGerm), without a draws x n matrix of them.
  // Rows padded by kPad zeros (a fresh LargeArray is zero).
  const std::size_t stride = static_cast<std::size_t>(draws) + kPad;
  univariate_ = LargeArray(static_cast<std::size_t>(n) * p * stride);
  std::vector<std::vector<double>> a(n, std::vector<double>(p + 1)), sb(n, std::vector<double>(p + 1));
  for (int d = 0; d < n; ++d) {
    const OrthonormalFamily& f = basis.family(d);
    for (int k = 0; k < p; ++k) a[d][k] = f.recurrenceA(k);
    for (int k = 1; k <= p; ++k) sb[d][k] = std::sqrt(f.recurrenceB(k));
  }
  // The germ values in chunks of draws (sampleGerms's order within and across
  // chunks), then each row of the chunk in turn: small memory, sequential
  // writes. The threads take contiguous runs of chunks, each with the stream
  // advanced to its first draw (one generator output per germ value), so the
  // values do not depend on the thread count.
  constexpr int kChunk = 1024;
  const int chunks = (draws + kChunk - 1) / kChunk;
  inParts(chunks, threads.count, [&](int chunk_begin, int chunk_end) {
    GermGenerator rng(seed);
    rng.discard(static_cast<unsigned long long>(chunk_begin) * kChunk * n);
    std::vector<double> chunk(static_cast<std::size_t>(kChunk) * n);  // draw-major
    for (int q0 = chunk_begin * kChunk; q0 < std::min(draws, chunk_end * kChunk); q0 += kChunk) {
      const int count = std::min(kChunk, draws - q0);
      for (int q = 0; q < count; ++q) {
        for (int d = 0; d < n; ++d) chunk[static_cast<std::size_t>(q) * n + d] = drawGerm(rng, basis.family(d));
      }
      for (int d = 0; d < n && p >= 1; ++d) {
        double* first = univariate_.data() + static_cast<std::size_t>(d) * p * stride + q0;
        for (int q = 0; q < count; ++q) first[q] = (chunk[static_cast<std::size_t>(q) * n + d] - a[d][0]) / sb[d][1];
        for (int k = 2; k <= p; ++k) {
          double* row = first + (k - 1) * stride;
          const double* prev = row - stride;
          for (int q = 0; q < count; ++q) {
            const double x = chunk[static_cast<std::size_t>(q) * n + d];
            const double before = k == 2 ? 1.0 : prev[q - static_cast<std::ptrdiff_t>(stride)];
            row[q] = ((x - a[d][k - 1]) * prev[q] - sb[d][k - 1] * before) / sb[d][k];
          }
        }
      }
    }
  });
  for (const std::vector<int>& index : basis.multiIndices()) {
    std::vector<int> rows;
    for (int d = 0; d < n; ++d) {
      if (index[d] > 0) rows.push_back(d * p + index[d] - 1);
    }
    factors_.push_back(std::move(rows));
  }
}

ParameterPdfSampler::ParameterPdfSampler(const PolynomialBasis& basis, int draws, int bins,
                                         std::uint64_t seed, int parameters, PdfSetupThreads threads)
    : terms_(basis.size()), draws_(draws), bins_(bins) {
  // Checked before any sampler is made (the message names the set's numbers).
  if (draws < 1 || bins < 1 || parameters < 0) {
    throw std::invalid_argument("ParameterPdfSampler: need draws, bins >= 1 and parameters >= 0 (got " +
                                std::to_string(draws) + ", " + std::to_string(bins) + ", " +
                                std::to_string(parameters) + ")");
  }
  std::vector<std::optional<ParameterPdfSampler>> made(static_cast<std::size_t>(parameters));
  inParts(parameters, threads.count, [&](int begin, int end) {
    for (int i = begin; i < end; ++i) made[i].emplace(basis, draws, bins, seed + i);
  });
  for (std::optional<ParameterPdfSampler>& m : made) per_parameter_.push_back(std::move(*m));
}

std::vector<Histogram> ParameterPdfSampler::histogramsOnFirstDraws(
    const Eigen::MatrixXd& coefficients, int threads) const {
  return per_parameter_.empty() ? histograms(coefficients, threads)
                                : per_parameter_.front().histograms(coefficients, threads);
}

std::vector<Histogram> ParameterPdfSampler::histograms(const Eigen::MatrixXd& coefficients,
                                                       int threads) const {
  threads = std::max(1, threads);
  if (!per_parameter_.empty()) {
    if (coefficients.rows() != static_cast<Eigen::Index>(per_parameter_.size())) {
      throw std::invalid_argument("ParameterPdfSampler: " + std::to_string(coefficients.rows()) +
                                  " quantities for a sampler of " +
                                  std::to_string(per_parameter_.size()) + " independent draw sets");
    }
    if (!coefficients.allFinite()) return {};
    std::vector<Histogram> out(per_parameter_.size());
    inParts(static_cast<int>(out.size()), threads, [&](int begin, int end) {
      for (int i = begin; i < end; ++i) out[i] = per_parameter_[i].histograms(coefficients.row(i)).front();
    });
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
  // The calling thread's buffer, kept for its next call (the node's PDF
  // worker calls every k-th sample): its pages are touched once. Only the
  // values written below are read.
  thread_local LargeArray values_buffer;
  const std::size_t needed = static_cast<std::size_t>(draws_ + kPad) * quantities;
  if (values_buffer.size() < needed) values_buffer = LargeArray(needed);
  Eigen::Map<Eigen::MatrixXd> values(values_buffer.data(), draws_ + kPad, quantities);
  // The terms some quantity uses. A term whose coefficients are all 0 adds
  // exactly 0 to each running sum: within one block (terms <= block_cols)
  // leaving it out changes no bit and spares its products (an expansion
  // linear in the germs uses 1 + n of its S terms).
  std::vector<int> used;
  for (int j = 0; j < terms_; ++j) {
    if (terms_ > block_cols || (coefficients.col(j).array() != 0.0).any()) used.push_back(j);
  }
  const int active = static_cast<int>(used.size());
  // Coefficients row by row, contiguous.
  std::vector<double> rows(static_cast<std::size_t>(quantities) * active);
  for (Eigen::Index r = 0; r < quantities; ++r) {
    for (int k = 0; k < active; ++k) rows[r * active + k] = coefficients(r, used[k]);
  }
  // Blocks of draws split among the threads: each value is its draw's sum
  // alone, so the split does not change a bit.
  const int blocks = (draws_ + kBlock - 1) / kBlock;
  inParts(blocks, threads, [&](int block_begin, int block_end) {
    std::vector<double> products(static_cast<std::size_t>(active) * (kBlock + kPad), 1.0);
    std::vector<const double*> psi(static_cast<std::size_t>(active));
    for (int q0 = block_begin * kBlock; q0 < std::min(draws_, block_end * kBlock); q0 += kBlock) {
      const int count = std::min(kBlock, draws_ - q0);
      for (int k = 0; k < active; ++k) {
        const std::vector<int>& f = factors_[static_cast<std::size_t>(used[k])];
        double* row = products.data() + static_cast<std::size_t>(k) * (kBlock + kPad);
        if (f.size() == 1) {  // one factor: its values as they are
          psi[k] = univariate_.data() + static_cast<std::size_t>(f[0]) * (draws_ + kPad) + q0;
          continue;
        }
        psi[k] = row;
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
        gemvOrderValues(psi.data(), rows.data() + r * active, active, block_cols, count,
                        values.col(r).data() + q0);
      }
    }
  });
  out.resize(static_cast<std::size_t>(quantities));
  inParts(static_cast<int>(quantities), threads, [&](int begin, int end) {
    for (int r = begin; r < end; ++r) out[r] = binned(values.col(r).head(draws_), bins_);
  });
  return out;
}

}  // namespace pc_ekf
