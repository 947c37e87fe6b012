// Which multi-indices a PC basis keeps (docs/method.md §3.3).
#pragma once

#include <string>
#include <vector>

namespace pc_ekf {

// Total degree keeps |alpha|_1 <= p. The hyperbolic cross keeps the
// multi-indices of q-norm (sum_i alpha_i^q)^(1/q) <= p, 0 < q <= 1: every
// univariate term up to degree p stays, and the smaller q, the fewer
// high-order interactions (q = 1 is total degree). Many uncertain parameters
// usually interact weakly, so q < 1 cuts S (and the points a regression
// needs) where total degree would grow as C(n + p, p).
enum class TruncationKind { kTotalDegree, kHyperbolic };
std::string toString(TruncationKind k);
TruncationKind truncationKindFromString(const std::string& name);  // throws std::invalid_argument

struct BasisTruncation {
  TruncationKind kind = TruncationKind::kTotalDegree;
  double q_norm = 1.0;  // hyperbolic only, in (0, 1]
  // Germs from this index on (a vehicle's tolerances, after the payload's
  // germs) enter a term at most one at a time: each interacts with the germs
  // before it, not with another of its kind. Most tolerances act on the
  // readings nearly additively, and their pairs are most of a total-degree
  // basis (n = 16, p = 2: S 153 -> 62). -1: no such limit.
  int single_from = -1;
};

// Multi-indices of q-norm <= order in `dimension` variables, in the graded
// order of totalDegreeMultiIndices (the total-degree set, filtered: the q-norm
// is at least the 1-norm for q <= 1). q = 1 gives the total-degree set.
// Throws std::invalid_argument for q outside (0, 1].
std::vector<std::vector<int>> hyperbolicMultiIndices(int dimension, int order, double q);

// The multi-indices `truncation` keeps at `order` (then at most one germ of
// index >= single_from per multi-index).
std::vector<std::vector<int>> truncatedMultiIndices(int dimension, int order,
                                                    const BasisTruncation& truncation);

}  // namespace pc_ekf
