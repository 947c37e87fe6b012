#include "pc_ekf/pc/scrambled_halton.h"

#include <numeric>
#include <stdexcept>
#include <vector>

#include "pc_ekf/pc/point_sets.h"

namespace pc_ekf {

namespace {

// SplitMix64's output function: a bijective 64-bit mixer.
std::uint64_t mix(std::uint64_t z) {
  z += 0x9E3779B97F4A7C15ULL;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

// Image of `digit` under the permutation of {0, ..., base - 1} that the key
// selects (Fisher-Yates driven by a SplitMix64 stream from the key).
int permutedDigit(int digit, int base, std::uint64_t key, std::vector<int>* scratch) {
  std::vector<int>& perm = *scratch;
  perm.resize(base);
  std::iota(perm.begin(), perm.end(), 0);
  std::uint64_t state = key;
  for (int i = base - 1; i > 0; --i) {
    state = mix(state);
    const int j = static_cast<int>(state % static_cast<std::uint64_t>(i + 1));
    std::swap(perm[i], perm[j]);
  }
  return perm[digit];
}

// K, the number of scrambled digits: the largest with base^K <= 2^50.
int digitCount(std::uint64_t base, std::uint64_t* scale) {
  int k = 0;
  std::uint64_t s = 1;
  while (s <= (std::uint64_t(1) << 50) / base) s *= base, ++k;
  *scale = s;
  return k;
}

}  // namespace

double scrambledRadicalInverse(std::uint64_t index, int base, int dimension, std::uint64_t seed) {
  if (base < 2) throw std::invalid_argument("scrambledRadicalInverse: base must be >= 2");
  const std::uint64_t b = static_cast<std::uint64_t>(base);
  std::uint64_t scale = 1;
  const int digits = digitCount(b, &scale);
  const std::uint64_t coordinate_key = mix(mix(seed) ^ static_cast<std::uint64_t>(dimension));
  std::vector<int> scratch;
  // The permutation of digit k depends on the unscrambled digits before it
  // (their integer value `prefix` and k): nested uniform scrambling.
  std::uint64_t prefix = 0, prefix_weight = 1, value = 0;
  for (int k = 0; k < digits; ++k) {
    const int digit = static_cast<int>(index % b);
    index /= b;
    const std::uint64_t key = mix(mix(coordinate_key ^ static_cast<std::uint64_t>(k)) ^ prefix);
    value = value * b + static_cast<std::uint64_t>(permutedDigit(digit, base, key, &scratch));
    prefix += static_cast<std::uint64_t>(digit) * prefix_weight;
    prefix_weight *= b;
  }
  return (static_cast<double>(value) + 0.5) / static_cast<double>(scale);
}

Eigen::MatrixXd scrambledHaltonPoints(int count, int dimension, std::uint64_t seed,
                                      std::uint64_t start) {
  if (count < 0 || dimension < 1) {
    throw std::invalid_argument("scrambledHaltonPoints: need count >= 0 and dimension >= 1");
  }
  const std::vector<int> primes = firstPrimes(dimension);
  Eigen::MatrixXd points(count, dimension);
  for (int q = 0; q < count; ++q) {
    for (int d = 0; d < dimension; ++d) {
      points(q, d) = scrambledRadicalInverse(start + q, primes[d], d, seed);
    }
  }
  return points;
}

}  // namespace pc_ekf
