#include "pc_ekf/pc/point_sets.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "pc_ekf/pc/orthonormal_family.h"

namespace pc_ekf {

double radicalInverse(std::uint64_t index, int base) {
  if (base < 2) throw std::invalid_argument("radicalInverse: base must be >= 2");
  // Reverse the digits as an integer first, divide once: exact for the small
  // indices used here and free of accumulated rounding.
  const std::uint64_t b = static_cast<std::uint64_t>(base);
  double reversed = 0.0;
  double scale = 1.0;
  while (index > 0) {
    reversed = reversed * base + static_cast<double>(index % b);
    scale *= base;
    index /= b;
  }
  return reversed / scale;
}

std::vector<int> firstPrimes(int dimension) {
  std::vector<int> primes;
  for (int candidate = 2; static_cast<int>(primes.size()) < dimension; ++candidate) {
    bool prime = true;
    for (int p : primes) {
      if (p * p > candidate) break;
      if (candidate % p == 0) {
        prime = false;
        break;
      }
    }
    if (prime) primes.push_back(candidate);
  }
  return primes;
}

Eigen::MatrixXd haltonPoints(int count, int dimension, std::uint64_t start) {
  if (count < 0 || dimension < 1) {
    throw std::invalid_argument("haltonPoints: need count >= 0 and dimension >= 1");
  }
  if (start == 0) throw std::invalid_argument("haltonPoints: index 0 maps to the boundary");
  const std::vector<int> primes = firstPrimes(dimension);
  Eigen::MatrixXd points(count, dimension);
  for (int q = 0; q < count; ++q) {
    for (int d = 0; d < dimension; ++d) points(q, d) = radicalInverse(start + q, primes[d]);
  }
  return points;
}

Eigen::MatrixXd hammersleyPoints(int count, int dimension) {
  if (count < 0 || dimension < 1) {
    throw std::invalid_argument("hammersleyPoints: need count >= 0 and dimension >= 1");
  }
  const std::vector<int> primes = firstPrimes(dimension);
  Eigen::MatrixXd points(count, dimension);
  for (int q = 0; q < count; ++q) {
    const int i = q + 1;
    points(q, 0) = (i - 0.5) / count;
    for (int d = 1; d < dimension; ++d) points(q, d) = radicalInverse(i, primes[d - 1]);
  }
  return points;
}

double maxCoordinateCorrelation(const Eigen::MatrixXd& points) {
  if (points.rows() < 2) return 0.0;
  const Eigen::MatrixXd centred = points.rowwise() - points.colwise().mean();
  const Eigen::MatrixXd cov = centred.transpose() * centred;
  double largest = 0.0;
  for (Eigen::Index i = 0; i < cov.rows(); ++i) {
    for (Eigen::Index j = 0; j < i; ++j) {
      const double denominator = std::sqrt(cov(i, i) * cov(j, j));
      if (denominator > 0.0) largest = std::max(largest, std::abs(cov(i, j)) / denominator);
    }
  }
  return largest;
}

Eigen::MatrixXd mapToGerms(const Eigen::MatrixXd& unit_points, const std::vector<GermSpec>& germs) {
  if (unit_points.cols() != static_cast<Eigen::Index>(germs.size())) {
    throw std::invalid_argument("mapToGerms: points have " + std::to_string(unit_points.cols()) +
                                " columns but there are " + std::to_string(germs.size()) +
                                " germs");
  }
  Eigen::MatrixXd mapped(unit_points.rows(), unit_points.cols());
  for (Eigen::Index d = 0; d < unit_points.cols(); ++d) {
    const OrthonormalFamily family(germs[d]);
    for (Eigen::Index q = 0; q < unit_points.rows(); ++q) {
      mapped(q, d) = family.inverseCdf(unit_points(q, d));
    }
  }
  return mapped;
}

}  // namespace pc_ekf
