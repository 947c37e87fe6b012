#include "pc_ekf/pc/collocation_design.h"

#include <limits>
#include <sstream>
#include <stdexcept>

#include "pc_ekf/pc/point_sets.h"

namespace pc_ekf {

std::string toString(PointSequence s) {
  switch (s) {
    case PointSequence::kHalton:
      return "halton";
    case PointSequence::kHammersley:
      return "hammersley";
    case PointSequence::kGauss:
      return "gauss";
  }
  throw std::invalid_argument("toString: unknown PointSequence value");
}

PointSequence pointSequenceFromString(const std::string& name) {
  if (name == "halton") return PointSequence::kHalton;
  if (name == "hammersley") return PointSequence::kHammersley;
  if (name == "gauss") return PointSequence::kGauss;
  throw std::invalid_argument("unknown collocation point sequence '" + name +
                              "' (accepted: halton, hammersley, gauss)");
}

CollocationDesign::CollocationDesign(const PolynomialBasis& basis, PointSequence sequence,
                                     int count, std::uint64_t halton_start, double max_condition) {
  const int n = basis.dimension();
  const int s = basis.size();
  if (count < 1) {
    throw std::invalid_argument("collocation design: point count must be positive, got " +
                                std::to_string(count));
  }
  // For the Gauss rule `count` is per dimension; compare the total to S before
  // building anything (count^n could be huge only for absurd configurations).
  double q_total = 1.0;
  for (int d = 0; d < (sequence == PointSequence::kGauss ? n : 1); ++d) q_total *= count;
  if (q_total < s) {
    std::ostringstream msg;
    msg << "collocation design degenerate: Q = " << q_total << " points < S = " << s
        << " basis terms (" << toString(sequence) << ", order " << basis.order() << " in " << n
        << " germs); least squares needs Q >= S (the paper uses Q >= 2S)";
    throw std::invalid_argument(msg.str());
  }

  Eigen::VectorXd weights;
  switch (sequence) {
    case PointSequence::kHalton:
      points_ = mapToGerms(haltonPoints(count, n, halton_start), basis.germs());
      break;
    case PointSequence::kHammersley:
      points_ = mapToGerms(hammersleyPoints(count, n), basis.germs());
      break;
    case PointSequence::kGauss:
      basis.tensorGaussRule(count, &points_, &weights);
      break;
  }
  design_ = basis.evaluate(points_);

  // For the Gauss rule the relevant matrix is W^(1/2) A (orthonormal columns when
  // the rule integrates degree 2p exactly); A alone is ill-conditioned merely
  // because tail nodes carry tiny weights.
  const Eigen::MatrixXd conditioned =
      sequence == PointSequence::kGauss
          ? Eigen::MatrixXd(weights.cwiseSqrt().asDiagonal() * design_)
          : design_;
  const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(conditioned).singularValues();
  condition_ =
      sv(sv.size() - 1) > 0.0 ? sv(0) / sv(sv.size() - 1) : std::numeric_limits<double>::infinity();
  if (!(condition_ <= max_condition)) {
    std::ostringstream msg;
    msg << "collocation design degenerate: condition number " << condition_ << " > "
        << max_condition << " (Q = " << pointCount() << " points, S = " << s << " basis terms, "
        << toString(sequence) << ")";
    throw std::invalid_argument(msg.str());
  }

  if (sequence == PointSequence::kGauss) {
    // Discrete projection c_j = sum_q w_q f(xi_q) psi_j(xi_q): exact for f of
    // degree <= 2 count - 1 - p per variable, no linear solve needed.
    projector_ = design_.transpose() * weights.asDiagonal();
  } else {
    // Least-squares pseudo-inverse, computed once from a rank-revealing
    // factorisation (never the normal equations, which square cond(A)).
    projector_ = Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>(design_).pseudoInverse();
  }
}

}  // namespace pc_ekf
