// Low-discrepancy point sets on the unit cube and their map to the germs (docs/method.md §3.4).
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <vector>

#include "pc_ekf/pc/germ.h"

namespace pc_ekf {

// Radical inverse of `index` in `base` (van der Corput): 1 -> 1/2, 2 -> 1/4 ... in base 2.
double radicalInverse(std::uint64_t index, int base);

// First `dimension` primes (2, 3, 5, ...).
std::vector<int> firstPrimes(int dimension);

// Halton points with indices start .. start + count - 1 (default 1..Q so no
// point sits on the boundary): row q, column d = radicalInverse(start + q, prime_d).
Eigen::MatrixXd haltonPoints(int count, int dimension, std::uint64_t start = 1);

// Hammersley set: first coordinate (i - 1/2)/count, i = 1..count, the others
// radical inverses of i in bases 2, 3, ...
Eigen::MatrixXd hammersleyPoints(int count, int dimension);

// Largest |Pearson correlation| between two coordinates (columns) of a point
// set: 0 for a design whose coordinates are uncorrelated; an i.i.d. uniform
// design of Q points has about sqrt(2 ln(n(n-1)/2) / Q) (0.17 at Q = 306, n = 15).
double maxCoordinateCorrelation(const Eigen::MatrixXd& points);

// Maps unit-cube points (rows) through each germ's inverse CDF.
Eigen::MatrixXd mapToGerms(const Eigen::MatrixXd& unit_points, const std::vector<GermSpec>& germs);

}  // namespace pc_ekf
