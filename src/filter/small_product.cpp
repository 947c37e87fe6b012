#include "pc_ekf/filter/small_product.h"

#if defined(__x86_64__)
#include <immintrin.h>
#endif

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

// The products on any x86-64 (the baseline instruction set: no fused
// multiply-adds).
void portableProduct(const double* __restrict a, const double* __restrict b,
                     Eigen::Index b_row_stride, Eigen::Index b_col_stride,
                     double* __restrict dst, Eigen::Index m, Eigen::Index k, Eigen::Index n) {
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

#if defined(__x86_64__)
// The products where the CPU has AVX2 and FMA (x86-64-v3): blocks of 8 rows
// (two vectors) and 4 columns of dst held in 8 registers, then a block of 4
// rows and single rows, so that the loads of a and b serve several sums (the one-column
// loops above waited on one chain of additions). Every entry is still summed
// over l in order, and fused or not as GCC compiled the one-column loops for
// x86-64-v3, so that the values are theirs bit for bit: every m with fused
// multiply-adds but 4 and 8 rows, which round the product first except in
// the last term of an odd k (those loops took l in pairs).
#define PC_EKF_AVX2_FMA __attribute__((target("avx2,fma")))

template <bool Fused>
PC_EKF_AVX2_FMA inline __m256d multiplyAdd(__m256d acc, __m256d a, __m256d b) {
  if constexpr (Fused) {
    return _mm256_fmadd_pd(a, b, acc);
  } else {
    __m256d p = _mm256_mul_pd(a, b);
    asm("" : "+x"(p));  // the rounded product: keeps the compiler from fusing
    return _mm256_add_pd(acc, p);
  }
}
template <bool Fused>
PC_EKF_AVX2_FMA inline double multiplyAdd(double acc, double a, double b) {
  if constexpr (Fused) {
    return __builtin_fma(a, b, acc);
  } else {
    double p = a * b;
    asm("" : "+x"(p));
    return acc + p;
  }
}

struct Operands {
  const double* a;  // the block's first row; leading dimension m
  const double* b;
  Eigen::Index b_row_stride, b_col_stride;
  double* dst;      // the block's first row; leading dimension m
  Eigen::Index m, k, n;
};

// Term l of the block's sums.
template <int V, int C, bool Fused>
PC_EKF_AVX2_FMA inline void vectorTerm(const Operands& o, const double* bj, Eigen::Index l,
                                 __m256d (&acc)[C][V]) {
  __m256d al[V];
  for (int v = 0; v < V; ++v) al[v] = _mm256_loadu_pd(o.a + l * o.m + 4 * v);
  for (int c = 0; c < C; ++c) {
    const __m256d blj = _mm256_broadcast_sd(bj + l * o.b_row_stride + c * o.b_col_stride);
    for (int v = 0; v < V; ++v) acc[c][v] = multiplyAdd<Fused>(acc[c][v], al[v], blj);
  }
}

// Rows [0, 4 V) of the block: V vectors per column, C columns at a time.
template <int V, int C, bool Fused>
PC_EKF_AVX2_FMA inline void vectorRows(const Operands& o, Eigen::Index j) {
  __m256d acc[C][V];
  for (int c = 0; c < C; ++c) {
    for (int v = 0; v < V; ++v) acc[c][v] = _mm256_setzero_pd();
  }
  const double* bj = o.b + j * o.b_col_stride;
  const Eigen::Index paired = (!Fused && o.k % 2 == 1) ? o.k - 1 : o.k;
  for (Eigen::Index l = 0; l < paired; ++l) vectorTerm<V, C, Fused>(o, bj, l, acc);
  if (paired < o.k) vectorTerm<V, C, true>(o, bj, paired, acc);
  for (int c = 0; c < C; ++c) {
    for (int v = 0; v < V; ++v) _mm256_storeu_pd(o.dst + (j + c) * o.m + 4 * v, acc[c][v]);
  }
}

// Rows [0, R) of the block (R < 4), C columns at a time.
template <int R, int C, bool Fused>
PC_EKF_AVX2_FMA inline void scalarRows(const Operands& o, Eigen::Index j) {
  double acc[C][R] = {};
  const double* bj = o.b + j * o.b_col_stride;
  for (Eigen::Index l = 0; l < o.k; ++l) {
    for (int c = 0; c < C; ++c) {
      const double blj = bj[l * o.b_row_stride + c * o.b_col_stride];
      for (int i = 0; i < R; ++i) acc[c][i] = multiplyAdd<Fused>(acc[c][i], o.a[l * o.m + i], blj);
    }
  }
  for (int c = 0; c < C; ++c) {
    for (int i = 0; i < R; ++i) o.dst[(j + c) * o.m + i] = acc[c][i];
  }
}

template <int V, bool Fused>
PC_EKF_AVX2_FMA void vectorBlock(const Operands& o) {
  Eigen::Index j = 0;
  for (; j + 4 <= o.n; j += 4) vectorRows<V, 4, Fused>(o, j);
  for (; j < o.n; ++j) vectorRows<V, 1, Fused>(o, j);
}
template <int R, bool Fused>
PC_EKF_AVX2_FMA void scalarBlock(const Operands& o) {
  Eigen::Index j = 0;
  for (; j + 4 <= o.n; j += 4) scalarRows<R, 4, Fused>(o, j);
  for (; j < o.n; ++j) scalarRows<R, 1, Fused>(o, j);
}

template <bool Fused>
PC_EKF_AVX2_FMA void blockedProduct(Operands o) {
  const double* a = o.a;
  double* dst = o.dst;
  Eigen::Index r = 0;
  for (; r + 8 <= o.m; r += 8) {
    o.a = a + r;
    o.dst = dst + r;
    vectorBlock<2, Fused>(o);
  }
  if (r + 4 <= o.m) {
    o.a = a + r;
    o.dst = dst + r;
    vectorBlock<1, Fused>(o);
    r += 4;
  }
  o.a = a + r;
  o.dst = dst + r;
  switch (o.m - r) {
    case 1: return scalarBlock<1, Fused>(o);
    case 2: return scalarBlock<2, Fused>(o);
    case 3: return scalarBlock<3, Fused>(o);
    default: return;
  }
}
#endif

}  // namespace

void smallProduct(const double* a, const double* b, Eigen::Index b_row_stride,
                  Eigen::Index b_col_stride, double* dst, Eigen::Index m, Eigen::Index k,
                  Eigen::Index n) {
#if defined(__x86_64__)
  static const bool v3 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  if (v3) {
    const Operands o{a, b, b_row_stride, b_col_stride, dst, m, k, n};
    return (m == 4 || m == 8) ? blockedProduct<false>(o) : blockedProduct<true>(o);
  }
#endif
  portableProduct(a, b, b_row_stride, b_col_stride, dst, m, k, n);
}

}  // namespace pc_ekf
