// Small dense products of the per-sample forecast, and a cheap finiteness test.
#pragma once

#include <Eigen/Dense>
#include <cmath>

namespace pc_ekf {

// dst (m x n, column-major) = a (m x k, column-major, leading dimension m) * b,
// b(l, j) = b[l * b_row_stride + j * b_col_stride]: the per-sample products
// X A^T and Y P^T (with AVX2 and FMA: blocks of 8 rows and 4 columns of dst
// in registers, any m; otherwise the column of dst in registers for m = 4
// and 8 to 12),
// where Eigen's blocked GEMM spends more on packing than on arithmetic. Each
// column of dst is summed over l in order, whatever n is: a column's value
// does not depend on which columns are computed with it.
void smallProduct(const double* a, const double* b, Eigen::Index b_row_stride,
                  Eigen::Index b_col_stride, double* dst, Eigen::Index m, Eigen::Index k,
                  Eigen::Index n);

// All entries finite, in one vectorised pass (x * 0 is NaN for NaN and +-Inf).
template <typename Derived>
bool allFiniteFast(const Eigen::DenseBase<Derived>& m) {
  return std::isfinite((m.derived().array() * 0.0).sum());
}

}  // namespace pc_ekf
