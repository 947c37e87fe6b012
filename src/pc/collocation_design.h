// Collocation points and the least-squares projector onto the basis (docs/method.md §3.4, §3.5).
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <string>

#include "pc_ekf/pc/polynomial_basis.h"
#include "pc_ekf/pc/setting_breach.h"

namespace pc_ekf {

// kScrambledHalton: Owen-scrambled Halton (scrambled_halton.h), seeded.
enum class PointSequence { kHalton, kHammersley, kGauss, kSmolyak, kScrambledHalton };
std::string toString(PointSequence s);
// The sequence `collocation.sequence: auto` (the default) picks for n germs:
// plain Halton up to kPlainHaltonMaxDimension, scrambled Halton above. At
// Q = 2 S (order 2) plain Halton's largest |correlation| between two
// coordinates stays within the scrambled design's seed-to-seed range
// (0.13-0.29 over 20 seeds) up to n = 12 and exceeds every seed's from n = 14
// (0.34-0.47 against at most 0.21; docs/method.md §3.4).
constexpr int kPlainHaltonMaxDimension = 12;
PointSequence defaultPointSequence(int dimension);
// The tensor Gauss rule `collocation.sequence: auto` takes when the config
// sets no point count: order + 1 nodes per germ (exact to degree 2 order + 1
// per germ: the order-p basis is orthonormal on the nodes), when its
// (order + 1)^dimension nodes are no more than `halton_points`, the Q of the
// regression design it replaces. Returns the nodes per germ, or 0 when the
// rule is costlier (auto then keeps defaultPointSequence). In two germs at
// order 4: 25 nodes against 30 Halton points, and a Monte-Carlo sample ratio
// of about 1500 against 17 (docs/performance.md).
int autoGaussNodes(int dimension, int order, int halton_points);
PointSequence pointSequenceFromString(const std::string& name);  // throws std::invalid_argument

// How values at the points become coefficients. kAuto: the quadrature for
// kGauss, least squares for the others, kSmolyak included: the filter
// re-projects at every sample, and a sparse grid's negative weights make its
// quadrature projection amplify the truncation error from step to step
// (measured on the paper case: 0.035 against 0.021 at level 4; unstable at
// n = 4 and 6), where least squares is an orthogonal projection.
enum class ProjectionMethod { kAuto, kRegression, kQuadrature };
std::string toString(ProjectionMethod m);
ProjectionMethod projectionMethodFromString(
    const std::string& name);  // throws std::invalid_argument

// The rules the settings of a design must keep for a basis of `terms` terms
// of total degree `order` in `dimension` germs: the quadrature projection
// needs a quadrature rule (gauss or smolyak), smolyak's quadrature projection
// a level of at least the order, and the least squares Q >= S (gauss: count
// nodes per germ). The breach's setting: "projection", "level" or "points"
// (the collocation: keys). CollocationDesign throws on the first one broken;
// the config parser names the key.
SettingBreach designRuleBreach(PointSequence sequence, int count, ProjectionMethod projection,
                                  int dimension, int order, std::size_t terms);

class CollocationDesign {
 public:
  // Builds points, A (Q x S) and the projector P (S x Q) with coeffs = P * values,
  // via column-pivoted QR / complete orthogonal decomposition (never normal
  // equations). For kGauss, `count` is the number of nodes per dimension and
  // the projection uses the quadrature weights (exact for degree <= 2n-1-p).
  // For kSmolyak, `count` is the sparse grid's level L (exact to total degree
  // 2L + 1, see sparse_grid.h); its quadrature projection needs L >= p, the
  // regression Q >= S.
  // Throws std::invalid_argument when a rule of designRuleBreach is broken
  // (Q < S among them) or cond(A) > max_condition, with a message giving Q,
  // S and the condition number.
  CollocationDesign(const PolynomialBasis& basis, PointSequence sequence, int count,
                    std::uint64_t halton_start = 1, double max_condition = 1e8,
                    ProjectionMethod projection = ProjectionMethod::kAuto,
                    bool nested = false,  // smolyak: nested rules where the germ has them
                    std::uint64_t scramble_seed = 1);  // scrambled_halton's permutations

  PointSequence sequence() const { return sequence_; }
  // The method in use (never kAuto).
  ProjectionMethod projection() const { return projection_; }

  int pointCount() const { return static_cast<int>(points_.rows()); }  // Q
  int termCount() const { return static_cast<int>(design_.cols()); }   // S
  const Eigen::MatrixXd& points() const { return points_; }           // Q x n (germ coordinates)
  const Eigen::MatrixXd& designMatrix() const { return design_; }      // A, Q x S
  const Eigen::MatrixXd& projector() const { return projector_; }      // S x Q
  // cond(A) from its singular values; for kGauss cond(W^(1/2) A), which is 1 when the
  // rule is exact to degree 2p (A alone grows with the tiny tail weights).
  double conditionNumber() const { return condition_; }

  // values: Q x m (one column per projected quantity) -> S x m coefficients.
  Eigen::MatrixXd project(const Eigen::MatrixXd& values) const { return projector_ * values; }
  // coefficients: m x S (row per quantity) -> m x Q values at the points.
  Eigen::MatrixXd evaluateAtPoints(const Eigen::MatrixXd& coefficients) const {
    return coefficients * design_.transpose();
  }

  // Leave-one-out error of the least-squares fit of the basis to values at
  // the points (rows = quantities, m x Q), per quantity, relative to the
  // spread of its values over the points: sqrt(sum_q e_q^2 / sum_q (v_q - mean)^2)
  // with e_q = r_q / (1 - h_qq), r the least-squares residual and h the
  // diagonal of the hat matrix A (A^T A)^-1 A^T (the closed form of refitting
  // without point q). For quadrature designs it is the error of the
  // least-squares fit on the same nodes, an estimate of the expansion's
  // truncation error. Empty when unavailable (Q = S: every h_qq = 1).
  Eigen::VectorXd leaveOneOutError(const Eigen::MatrixXd& values) const;
  bool hasLeaveOneOut() const { return loo_scale_.size() > 0; }
  // Pieces of leaveOneOutError for callers that sum over the points
  // themselves: the pseudo-inverse of A (S x Q) and 1 / (1 - h_qq).
  const Eigen::MatrixXd& leastSquaresProjector() const {
    return ls_projector_.size() > 0 ? ls_projector_ : projector_;
  }
  const Eigen::VectorXd& leaveOneOutScale() const { return loo_scale_; }
  const Eigen::VectorXd& hatDiagonal() const { return hat_diagonal_; }

 private:
  Eigen::MatrixXd points_;
  Eigen::MatrixXd design_;
  Eigen::MatrixXd projector_;
  Eigen::MatrixXd ls_projector_;  // pseudo-inverse of A (empty: projector_ is it)
  Eigen::VectorXd hat_diagonal_;  // h_qq
  Eigen::VectorXd loo_scale_;     // 1 / (1 - h_qq), empty when some h_qq = 1
  PointSequence sequence_ = PointSequence::kHalton;
  ProjectionMethod projection_ = ProjectionMethod::kRegression;
  double condition_ = 0.0;
};

}  // namespace pc_ekf
