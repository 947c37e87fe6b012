// smallProduct: the forecast's products X A^T, Y P^T and H Y, for every row
// count, both operand layouts and column counts that do not fill a block.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstring>

#include "pc_ekf/filter/small_product.h"

namespace pc_ekf {
namespace {

// acc + a b with the product rounded first (no fused multiply-add).
double roundedMultiplyAdd(double acc, double a, double b) {
  volatile double p = a * b;
  return acc + p;
}

bool fusedMultiplyAdds() {
#if defined(__x86_64__)
  return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
  return false;
#endif
}

// Entry (i, j) summed over l in order, as the one-column loops summed it: on
// x86-64-v3 with fused multiply-adds except for 4 and 8 rows, whose last term
// of an odd k is fused.
Eigen::MatrixXd orderedProduct(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  const Eigen::Index m = a.rows(), k = a.cols();
  const bool v3 = fusedMultiplyAdds(), rounded_rows = m == 4 || m == 8;
  Eigen::MatrixXd d(m, b.cols());
  for (Eigen::Index j = 0; j < b.cols(); ++j) {
    for (Eigen::Index i = 0; i < m; ++i) {
      double acc = 0.0;
      for (Eigen::Index l = 0; l < k; ++l) {
        const bool fused = v3 && (!rounded_rows || (k % 2 == 1 && l == k - 1));
        acc = fused ? std::fma(a(i, l), b(l, j), acc) : roundedMultiplyAdd(acc, a(i, l), b(l, j));
      }
      d(i, j) = acc;
    }
  }
  return d;
}

TEST(SmallProduct, EveryEntryIsItsSumInOrderBitForBit) {
  int cases = 0;
  for (Eigen::Index m = 1; m <= 31; ++m) {
    for (Eigen::Index k : {1, 2, 7, 8, 78, 161}) {
      for (Eigen::Index n : {1, 3, 6, 160}) {
        const Eigen::MatrixXd a = Eigen::MatrixXd::Random(m, k);
        const Eigen::MatrixXd b = Eigen::MatrixXd::Random(k, n);
        const Eigen::MatrixXd expected = orderedProduct(a, b);
        // b column-major (row stride 1) and b^T column-major (row stride n).
        const Eigen::MatrixXd bt = b.transpose();
        Eigen::MatrixXd by_columns(m, n), by_rows(m, n);
        smallProduct(a.data(), b.data(), 1, k, by_columns.data(), m, k, n);
        smallProduct(a.data(), bt.data(), n, 1, by_rows.data(), m, k, n);
        ASSERT_EQ(0, std::memcmp(expected.data(), by_columns.data(), sizeof(double) * m * n))
            << "m " << m << " k " << k << " n " << n << " (b by columns)";
        ASSERT_EQ(0, std::memcmp(expected.data(), by_rows.data(), sizeof(double) * m * n))
            << "m " << m << " k " << k << " n " << n << " (b by rows)";
        // And the product itself, whatever the order: within the sums' round-off.
        const Eigen::MatrixXd eigen = a * b;
        const double scale = (a.cwiseAbs() * b.cwiseAbs()).maxCoeff();
        EXPECT_LE((by_columns - eigen).cwiseAbs().maxCoeff(), 4.0 * k * 1.1e-16 * scale);
        ++cases;
      }
    }
  }
  EXPECT_EQ(cases, 31 * 6 * 4);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
