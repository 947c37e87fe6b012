// Randomised Halton points: Owen's nested uniform scrambling of the radical
// inverse in each prime base (docs/method.md §3.4).
//
// Plain Halton coordinates in large bases are nearly linear in the index at a
// few hundred points (base 43: digit 1 = q mod 43, digit 2 = q / 43), so pairs
// of such coordinates are correlated, and an order-2 least-squares fit
// attributes variance to the wrong germs (vehicle_live.yaml, n = 15, Q = 306:
// max |correlation| 0.45 between coordinates). Scrambling permutes digit k of
// coordinate d with a permutation drawn from (seed, d, k, digits 1..k-1):
// every coordinate stays stratified like Halton's (each b^k-adic interval
// keeps its count), while different coordinates become independent.
#pragma once

#include <Eigen/Dense>
#include <cstdint>

namespace pc_ekf {

// Scrambled radical inverse of `index` in `base` for coordinate `dimension`
// under `seed`: digits down to b^-K with b^K <= 2^50, then the finest cell's
// midpoint, so that the value lies strictly inside (0, 1).
double scrambledRadicalInverse(std::uint64_t index, int base, int dimension, std::uint64_t seed);

// Rows start .. start + count - 1 of the scrambled Halton sequence in the
// first `dimension` prime bases; the same seed gives the same points, and the
// first Q points do not change when Q grows (nested like Halton).
Eigen::MatrixXd scrambledHaltonPoints(int count, int dimension, std::uint64_t seed,
                                      std::uint64_t start = 1);

}  // namespace pc_ekf
