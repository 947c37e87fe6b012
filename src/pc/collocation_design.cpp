#include "pc_ekf/pc/collocation_design.h"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "pc_ekf/pc/point_sets.h"
#include "pc_ekf/pc/scrambled_halton.h"
#include "pc_ekf/pc/sparse_grid.h"

namespace pc_ekf {

std::string toString(PointSequence s) {
  switch (s) {
    case PointSequence::kHalton:
      return "halton";
    case PointSequence::kHammersley:
      return "hammersley";
    case PointSequence::kGauss:
      return "gauss";
    case PointSequence::kSmolyak:
      return "smolyak";
    case PointSequence::kScrambledHalton:
      return "scrambled_halton";
  }
  throw std::invalid_argument("toString: unknown PointSequence value");
}

PointSequence defaultPointSequence(int dimension) {
  return dimension > kPlainHaltonMaxDimension ? PointSequence::kScrambledHalton
                                              : PointSequence::kHalton;
}

int autoGaussNodes(int dimension, int order, int halton_points) {
  if (dimension < 1 || order < 0) return 0;
  const double nodes = std::pow(static_cast<double>(order + 1), dimension);
  return nodes <= halton_points ? order + 1 : 0;
}

std::string toString(ProjectionMethod m) {
  switch (m) {
    case ProjectionMethod::kAuto:
      return "auto";
    case ProjectionMethod::kRegression:
      return "regression";
    case ProjectionMethod::kQuadrature:
      return "quadrature";
  }
  throw std::invalid_argument("toString: unknown ProjectionMethod value");
}

ProjectionMethod projectionMethodFromString(const std::string& name) {
  if (name == "auto") return ProjectionMethod::kAuto;
  if (name == "regression") return ProjectionMethod::kRegression;
  if (name == "quadrature") return ProjectionMethod::kQuadrature;
  throw std::invalid_argument("unknown collocation projection '" + name +
                              "' (accepted: auto, regression, quadrature)");
}

PointSequence pointSequenceFromString(const std::string& name) {
  if (name == "halton") return PointSequence::kHalton;
  if (name == "hammersley") return PointSequence::kHammersley;
  if (name == "gauss") return PointSequence::kGauss;
  if (name == "smolyak") return PointSequence::kSmolyak;
  if (name == "scrambled_halton") return PointSequence::kScrambledHalton;
  throw std::invalid_argument("unknown collocation point sequence '" + name +
                              "' (accepted: halton, scrambled_halton, hammersley, gauss, smolyak)");
}

SettingBreach designRuleBreach(PointSequence sequence, int count, ProjectionMethod projection,
                                  int dimension, int order, std::size_t terms) {
  const bool quadrature_rule =
      sequence == PointSequence::kGauss || sequence == PointSequence::kSmolyak;
  if (projection == ProjectionMethod::kQuadrature && !quadrature_rule) {
    return {"projection", "'quadrature'",
            "regression or auto for sequence " + toString(sequence) +
                " (the quadrature projection needs a quadrature rule: gauss or smolyak)"};
  }
  if (sequence == PointSequence::kSmolyak && projection == ProjectionMethod::kQuadrature &&
      count < order) {
    return {"level", std::to_string(count),
            "at least the order, " + std::to_string(order) +
                ", for the quadrature projection (level " + std::to_string(count) +
                " integrates total degree " + std::to_string(smolyakExactDegree(count)) +
                " exactly, the projection needs " + std::to_string(2 * order) +
                "), or projection: regression"};
  }
  // For the Gauss rule `count` is per dimension; the total is compared to S
  // before anything is built (count^n could be huge only for absurd settings).
  const double q = sequence == PointSequence::kGauss ? std::pow(count, dimension) : count;
  if (sequence != PointSequence::kSmolyak && q < static_cast<double>(terms)) {
    std::ostringstream needs;
    needs << "at least S = " << terms << " collocation points, the basis terms of order " << order
          << " in " << dimension << " germs (" << toString(sequence) << ": Q = " << q
          << " points < S: degenerate); least squares needs Q >= S (the paper uses Q >= 2S)";
    return {"points", std::to_string(count), needs.str()};
  }
  return {};
}

namespace {

std::vector<OrthonormalFamily> familiesOf(const PolynomialBasis& basis) {
  std::vector<OrthonormalFamily> families;
  for (int d = 0; d < basis.dimension(); ++d) families.push_back(basis.family(d));
  return families;
}

}  // namespace

CollocationDesign::CollocationDesign(const PolynomialBasis& basis, PointSequence sequence,
                                     int count, std::uint64_t halton_start, double max_condition,
                                     ProjectionMethod projection, bool nested,
                                     std::uint64_t scramble_seed)
    : sequence_(sequence) {
  const int n = basis.dimension();
  const int s = basis.size();
  if (count < 1 && !(sequence == PointSequence::kSmolyak && count == 0)) {
    throw std::invalid_argument("collocation design: point count must be positive, got " +
                                std::to_string(count));
  }
  const SettingBreach breach = designRuleBreach(sequence, count, projection, n, basis.order(),
                                                static_cast<std::size_t>(s));
  if (breach.broken()) {
    throw std::invalid_argument("collocation design: " + breach.setting + " " + breach.value +
                                ", needs " + breach.needs);
  }
  if (projection == ProjectionMethod::kAuto) {
    projection = sequence == PointSequence::kGauss ? ProjectionMethod::kQuadrature
                                                   : ProjectionMethod::kRegression;
  }
  projection_ = projection;

  Eigen::VectorXd weights;
  switch (sequence) {
    case PointSequence::kHalton:
      points_ = mapToGerms(haltonPoints(count, n, halton_start), basis.germs());
      break;
    case PointSequence::kScrambledHalton:
      points_ = mapToGerms(scrambledHaltonPoints(count, n, scramble_seed, halton_start),
                           basis.germs());
      break;
    case PointSequence::kHammersley:
      points_ = mapToGerms(hammersleyPoints(count, n), basis.germs());
      break;
    case PointSequence::kGauss:
      basis.tensorGaussRule(count, &points_, &weights);
      break;
    case PointSequence::kSmolyak: {
      SparseGridRule rule = smolyakRule(familiesOf(basis), count, nested);
      points_ = std::move(rule.nodes);
      weights = std::move(rule.weights);
      if (points_.rows() < s) {
        std::ostringstream msg;
        msg << "collocation design degenerate: smolyak level " << count
            << " has Q = " << points_.rows() << " points < S = " << s << " basis terms (order "
            << basis.order() << " in " << n << " germs); raise collocation.level";
        throw std::invalid_argument(msg.str());
      }
      break;
    }
  }
  design_ = basis.evaluate(points_);

  // For the Gauss rule the relevant matrix is W^(1/2) A (orthonormal columns when
  // the rule integrates degree 2p exactly); A alone is ill-conditioned merely
  // because tail nodes carry tiny weights. Sparse-grid weights can be negative:
  // there A itself (the regression matrix) is checked.
  const Eigen::MatrixXd conditioned =
      sequence == PointSequence::kGauss
          ? Eigen::MatrixXd(weights.cwiseSqrt().asDiagonal() * design_)
          : design_;
  // Singular values only (the check and conditionNumber()): divide and conquer
  // (a third of one-sided Jacobi's time at 160 x 78).
  const Eigen::VectorXd sv = Eigen::BDCSVD<Eigen::MatrixXd>(conditioned).singularValues();
  condition_ =
      sv(sv.size() - 1) > 0.0 ? sv(0) / sv(sv.size() - 1) : std::numeric_limits<double>::infinity();
  if (!(condition_ <= max_condition)) {
    std::ostringstream msg;
    msg << "collocation design degenerate: condition number " << condition_ << " > "
        << max_condition << " (Q = " << pointCount() << " points, S = " << s << " basis terms, "
        << toString(sequence) << ")";
    throw std::invalid_argument(msg.str());
  }

  // Least-squares pseudo-inverse, computed once from a rank-revealing
  // factorisation (never the normal equations, which square cond(A)).
  Eigen::MatrixXd least_squares =
      Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>(design_).pseudoInverse();
  if (projection_ == ProjectionMethod::kQuadrature) {
    // Discrete projection c_j = sum_q w_q f(xi_q) psi_j(xi_q): for Gauss exact
    // for f of degree <= 2 count - 1 - p per variable, no linear solve needed.
    projector_ = design_.transpose() * weights.asDiagonal();
    ls_projector_ = std::move(least_squares);
  } else {
    projector_ = std::move(least_squares);
  }
  // Hat matrix diagonal h_qq = (A A^+)_qq; Q = S (interpolation) leaves no
  // point out, so no leave-one-out error.
  const Eigen::MatrixXd& pinv = leastSquaresProjector();
  hat_diagonal_ = (design_.array() * pinv.transpose().array()).rowwise().sum();
  if ((hat_diagonal_.array() < 1.0 - 1e-10).all()) {
    loo_scale_ = (1.0 - hat_diagonal_.array()).inverse();
  }
}

Eigen::VectorXd CollocationDesign::leaveOneOutError(const Eigen::MatrixXd& values) const {
  if (!hasLeaveOneOut()) return Eigen::VectorXd();
  if (values.cols() != pointCount()) {
    throw std::invalid_argument("leaveOneOutError: values have " + std::to_string(values.cols()) +
                                " columns for " + std::to_string(pointCount()) + " points");
  }
  const Eigen::MatrixXd& pinv = leastSquaresProjector();
  const Eigen::MatrixXd fitted = (values * pinv.transpose()) * design_.transpose();
  const Eigen::ArrayXXd loo = (values - fitted).array().rowwise() * loo_scale_.transpose().array();
  Eigen::VectorXd out(values.rows());
  for (Eigen::Index i = 0; i < values.rows(); ++i) {
    const double spread = (values.row(i).array() - values.row(i).mean()).square().sum();
    const double err = loo.row(i).square().sum();
    // Values equal at every point (e.g. at rest) fit exactly: no error to report,
    // whatever rounding leaves in the residual.
    const double floor = 1e-24 * values.row(i).squaredNorm();
    out(i) = spread > floor ? std::sqrt(err / spread) : 0.0;
  }
  return out;
}

}  // namespace pc_ekf
