#include "pc_ekf/filter/small_product.h"

namespace pc_ekf {

namespace {

template <int M>
__attribute__((always_inline)) inline void smallProductRows(
    const double* __restrict a, const double* __restrict b, Eigen::Index b_row_stride,
    Eigen::Index b_col_stride, double* __restrict dst, Eigen::Index k, Eigen::Index n) {
  for (Eigen::Index j = 0; j < n; ++j) {
    double acc[M] = {};
    for (Eigen::Index l = 0; l < k; ++l) {
      const double blj = b[l * b_row_stride + j * b_col_stride];
      for (int i = 0; i < M; ++i) acc[i] += a[l * M + i] * blj;
    }
    for (int i = 0; i < M; ++i) dst[j * M + i] = acc[i];
  }
}

// Four rows (the measured channels): one column's sums form one chain of
// dependent additions, so four columns are summed side by side. Each column
// is still summed over l in order.
__attribute__((always_inline)) inline void smallProductFourRows(
    const double* __restrict a, const double* __restrict b, Eigen::Index b_row_stride,
    Eigen::Index b_col_stride, double* __restrict dst, Eigen::Index k, Eigen::Index n) {
  Eigen::Index j = 0;
  for (; j + 4 <= n; j += 4) {
    double acc[4][4] = {};
    for (Eigen::Index l = 0; l < k; ++l) {
      for (int c = 0; c < 4; ++c) {
        const double blj = b[l * b_row_stride + (j + c) * b_col_stride];
        for (int i = 0; i < 4; ++i) acc[c][i] += a[l * 4 + i] * blj;
      }
    }
    for (int c = 0; c < 4; ++c) {
      for (int i = 0; i < 4; ++i) dst[(j + c) * 4 + i] = acc[c][i];
    }
  }
  smallProductRows<4>(a, b + j * b_col_stride, b_row_stride, b_col_stride, dst + j * 4, k, n - j);
}

}  // namespace

// Compiled for x86-64-v3 and the baseline.
__attribute__((target_clones("arch=x86-64-v3", "default"))) void smallProduct(
    const double* __restrict a, const double* __restrict b, Eigen::Index b_row_stride,
    Eigen::Index b_col_stride, double* __restrict dst, Eigen::Index m, Eigen::Index k,
    Eigen::Index n) {
  switch (m) {
    case 4: return smallProductFourRows(a, b, b_row_stride, b_col_stride, dst, k, n);
    case 8: return smallProductRows<8>(a, b, b_row_stride, b_col_stride, dst, k, n);
    case 9: return smallProductRows<9>(a, b, b_row_stride, b_col_stride, dst, k, n);
    case 10: return smallProductRows<10>(a, b, b_row_stride, b_col_stride, dst, k, n);
    case 11: return smallProductRows<11>(a, b, b_row_stride, b_col_stride, dst, k, n);
    case 12: return smallProductRows<12>(a, b, b_row_stride, b_col_stride, dst, k, n);
    default: break;
  }
  for (Eigen::Index j = 0; j < n; ++j) {
    double* __restrict d = dst + j * m;
    for (Eigen::Index i = 0; i < m; ++i) d[i] = 0.0;
    for (Eigen::Index l = 0; l < k; ++l) {
      const double blj = b[l * b_row_stride + j * b_col_stride];
      const double* __restrict al = a + l * m;
      for (Eigen::Index i = 0; i < m; ++i) d[i] += al[i] * blj;
    }
  }
}

}  // namespace pc_ekf
