// Statistics of PC expansions from their coefficients (docs/method.md §3.6).
// Coefficient matrices hold one quantity per row, one basis term per column;
// column 0 is the mean (psi_1 = 1).
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <random>

#include "pc_ekf/pc/germ_generator.h"
#include "pc_ekf/pc/polynomial_basis.h"

namespace pc_ekf {

Eigen::VectorXd pcMean(const Eigen::MatrixXd& coefficients);
// Sum over j >= 2 of a_j b_j^T.
Eigen::MatrixXd pcCovariance(const Eigen::MatrixXd& coefficients);
Eigen::VectorXd pcStddev(const Eigen::MatrixXd& coefficients);

// Normalised histogram (unit area) of one expansion, from `draws` seeded germ samples.
struct Histogram {
  Eigen::VectorXd edges;      // bins + 1
  Eigen::VectorXd densities;  // bins
  Eigen::VectorXd centres() const;
};
// Bins span [lo, hi]; when lo >= hi the sample range is used. Samples outside are
// counted in `outside_mass` and not in the bins.
Histogram pcHistogram(const PolynomialBasis& basis, const Eigen::VectorXd& coefficients,
                      int draws, int bins, std::uint64_t seed, double lo = 0.0, double hi = 0.0,
                      double* outside_mass = nullptr);

// How Eigen's column-major matrix-vector product `values = psi * c` (psi:
// rows x terms) sums each value: from zero, term after term within blocks of
// gemvBlockColumns(rows, terms) terms, each block's sum added to the running
// value (one block when terms < 128). No fused multiply-add (a plain x86-64
// build). gemvValue repeats that sum for one row, so a value it gives equals
// the product's bit for bit (ParameterPdfSampler, HealthMonitor).
int gemvBlockColumns(Eigen::Index rows, Eigen::Index terms);
// psi_row: the row's `terms` values, `stride` apart (psi.data() + row,
// psi.rows() for the matrix itself; 1 for a column of its transpose).
double gemvValue(const double* psi_row, Eigen::Index stride, const double* c, Eigen::Index terms,
                 int block_cols);

// values[b] = the product's value for `count` draws (psi[j]: term j's values
// at the draws, contiguous; c: the S coefficients), summed as gemvValue sums
// them, four draws per AVX2 register where the CPU has it. psi[j] must be
// readable 16 values past `count` (rows padded).
void gemvOrderValues(const double* const* psi, const double* c, int terms, int block_cols,
                     int count, double* values);

// One germ value of sampleGerms's stream: 53 random bits of std::mt19937_64's
// stream (GermGenerator), offset by half a unit (u strictly inside (0, 1), the
// same stream on every standard library), through the family's inverse CDF.
inline double drawGerm(GermGenerator& rng, const OrthonormalFamily& family) {
  const double u = (static_cast<double>(rng() >> 11) + 0.5) * 0x1.0p-53;
  return family.inverseCdf(u);
}

// Samples the germ (rows = draws) with a seeded generator: draw after draw,
// germ after germ of drawGerm.
Eigen::MatrixXd sampleGerms(const PolynomialBasis& basis, int draws, std::uint64_t seed);

}  // namespace pc_ekf
