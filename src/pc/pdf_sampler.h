// Parameter PDFs: the histograms of pcHistogram (same germ draws, same
// binning, same arithmetic, so the same numbers) for every parameter at once,
// at a cost that does not grow with the draws times the terms per parameter.
// One seeded set of germ draws serves every parameter. The draws and their
// univariate polynomial values are computed once, at construction; a call
// then forms the basis in cache-sized blocks of draws (a term of total
// degree p is a product of at most p of those values) and accumulates every
// parameter's expansion from that one block (docs/realtime.md).
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <vector>

#include "pc_ekf/pc/large_array.h"
#include "pc_ekf/pc/pc_statistics.h"
#include "pc_ekf/pc/polynomial_basis.h"

namespace pc_ekf {

// Threads sharing a ParameterPdfSampler's construction (the same numbers for
// any count).
struct PdfSetupThreads {
  int count = 1;
};

class ParameterPdfSampler {
 public:
  // The draws are sampleGerms(basis, draws, seed): pcHistogram(basis, c,
  // draws, bins, seed) of each parameter gives histograms()'s numbers.
  ParameterPdfSampler(const PolynomialBasis& basis, int draws, int bins, std::uint64_t seed,
                      PdfSetupThreads threads = {});
  // Independent draws per parameter (pdf.shared_draws: false): row i of
  // histograms() uses sampleGerms(basis, draws, seed + i), as pcHistogram(...,
  // seed + i) does; `parameters` rows, each at the cost of a shared call.
  ParameterPdfSampler(const PolynomialBasis& basis, int draws, int bins, std::uint64_t seed,
                      int parameters, PdfSetupThreads threads = {});
  // Histogram of each row of `coefficients` (quantities x S terms), binned
  // over its sample range; none when a coefficient is not finite.
  // `threads` share the work (the same numbers for any count).
  std::vector<Histogram> histograms(const Eigen::MatrixXd& coefficients, int threads = 1) const;
  // Every row on the draws of `seed` itself (the shared draws, or the first
  // parameter's set): pcHistogram(basis, row, draws, bins, seed)'s numbers
  // for any number of rows.
  std::vector<Histogram> histogramsOnFirstDraws(const Eigen::MatrixXd& coefficients,
                                                int threads = 1) const;
  int draws() const { return draws_; }
  int terms() const { return terms_; }
  int bins() const { return bins_; }

 private:
  int terms_;
  int draws_;
  int bins_;
  // Row (d * order + k - 1): psi_k of germ d at every draw (psi_0 = 1 is exact
  // and left out of the products, which does not change their bits).
  LargeArray univariate_;
  std::vector<std::vector<int>> factors_;  // per term: rows of univariate_, ascending d
  std::vector<ParameterPdfSampler> per_parameter_;  // independent draws: one per row
};

}  // namespace pc_ekf
