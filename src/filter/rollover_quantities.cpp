#include "pc_ekf/filter/rollover_quantities.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "pc_ekf/pc/sparse_grid.h"

namespace pc_ekf {
namespace {

// Rows of the model's values in the full parameter vector: the roll plane's
// (bar_mass, bar_length, unsprung_mass_left/right) or the full car's
// (body_mass, track_width, unsprung_mass_front/rear, each per wheel: two
// wheels an axle).
struct RolloverRows {
  int bar_mass = -1, added_mass = -1, mount_height = -1, body_cg_height = -1,
      added_mass_height = -1, wheel_radius = -1, track = -1, gravity = -1;
  std::vector<int> unsprung;  // every unsprung_mass_*
  double wheels_per_unsprung = 1.0;  // the full car's are per axle's wheel
  bool complete() const {
    return std::min({bar_mass, added_mass, mount_height, body_cg_height, added_mass_height,
                     wheel_radius, track, gravity}) >= 0 &&
           !unsprung.empty();
  }
};

RolloverRows rowsOf(const ParameterMapping& mapping) {
  RolloverRows r;
  const std::vector<std::string>& names = mapping.modelParameterNames();
  for (int i = 0; i < static_cast<int>(names.size()); ++i) {
    const std::string& n = names[i];
    if (n == "bar_mass" || n == "body_mass") r.bar_mass = i;
    if (n == "added_mass") r.added_mass = i;
    if (n == "mount_height") r.mount_height = i;
    if (n == "body_cg_height") r.body_cg_height = i;
    if (n == "added_mass_height") r.added_mass_height = i;
    if (n == "wheel_radius") r.wheel_radius = i;
    if (n == "bar_length") r.track = i;  // the roll plane's track
    if (n == "track_width") {
      r.track = i;  // the full car's, w
      r.wheels_per_unsprung = 2.0;
    }
    if (n == "gravity") r.gravity = i;
    if (n.rfind("unsprung_mass", 0) == 0) r.unsprung.push_back(i);
  }
  return r;
}

// Tensor rules above this many nodes give way to a sparse grid.
constexpr double kMaxTensorNodes = 20000.0;

}  // namespace

const std::vector<std::string>& rolloverQuantityNames() {
  static const std::vector<std::string> names{"cg_height", "static_stability_factor",
                                              "rollover_threshold"};
  return names;
}

bool hasRolloverQuantities(const ParameterMapping& mapping) {
  const RolloverRows r = rowsOf(mapping);
  return r.complete() && mapping.nominalParameters()(r.mount_height) > 0.0;
}

Eigen::MatrixXd rolloverValues(const ParameterMapping& mapping, const Eigen::MatrixXd& full) {
  const RolloverRows r = rowsOf(mapping);
  if (!r.complete()) throw std::invalid_argument("rolloverValues: the model has no heights");
  Eigen::MatrixXd out(3, full.cols());
  for (Eigen::Index q = 0; q < full.cols(); ++q) {
    const auto p = full.col(q);
    const double m = p(r.bar_mass), M = p(r.added_mass);
    double unsprung = 0.0;
    for (int i : r.unsprung) unsprung += p(i);
    unsprung *= r.wheels_per_unsprung;
    const double first_moment = m * p(r.body_cg_height) + M * p(r.added_mass_height);  // S
    const double h = ((m + M) * p(r.mount_height) + first_moment + unsprung * p(r.wheel_radius)) /
                     (m + M + unsprung);
    const double ssf = p(r.track) / (2.0 * h);
    out(0, q) = h;
    out(1, q) = ssf;
    out(2, q) = p(r.gravity) * ssf;
  }
  return out;
}

void projectionRule(const PolynomialBasis& basis, Eigen::MatrixXd* nodes,
                    Eigen::VectorXd* weights) {
  const int n = basis.order() + 4;
  if (std::pow(double(n), basis.dimension()) <= kMaxTensorNodes) {
    basis.tensorGaussRule(n, nodes, weights);
    return;
  }
  std::vector<OrthonormalFamily> families;
  for (int d = 0; d < basis.dimension(); ++d) families.push_back(basis.family(d));
  SparseGridRule rule = smolyakRule(families, basis.order() + 1);
  *nodes = std::move(rule.nodes);
  *weights = std::move(rule.weights);
}

Eigen::MatrixXd projectValues(const PolynomialBasis& basis, const Eigen::MatrixXd& nodes,
                              const Eigen::VectorXd& weights, const Eigen::MatrixXd& values) {
  // Orthonormal basis: c_j = E[f psi_j] = sum_q w_q f(xi_q) psi_j(xi_q).
  const Eigen::MatrixXd psi = basis.evaluate(nodes);  // Q x S
  return values * weights.asDiagonal() * psi;
}

DerivedExpansions rolloverExpansions(const ParameterMapping& mapping, const PolynomialBasis& basis,
                                     const Eigen::MatrixXd& parameter_coefficients) {
  DerivedExpansions out;
  if (!hasRolloverQuantities(mapping) || parameter_coefficients.size() == 0 ||
      !parameter_coefficients.allFinite() || parameter_coefficients.cols() != basis.size() ||
      parameter_coefficients.rows() != mapping.count()) {
    return out;
  }
  // The rule and the basis at its nodes, once per basis and thread (the node
  // projects at every published sample; a sparse grid has thousands of nodes).
  // Keyed by the basis's content (germs, order, multi-indices).
  struct Rule {
    std::vector<GermSpec> germs;
    int order = -1;
    std::vector<std::vector<int>> indices;
    Eigen::MatrixXd psi;  // Q x S
    Eigen::VectorXd weights;
  };
  thread_local Rule rule;
  const auto same_germs = [&] {
    if (rule.germs.size() != basis.germs().size()) return false;
    for (std::size_t i = 0; i < rule.germs.size(); ++i) {
      const GermSpec &a = rule.germs[i], &b = basis.germs()[i];
      if (a.family != b.family || a.alpha != b.alpha || a.beta != b.beta) return false;
    }
    return true;
  };
  if (rule.order != basis.order() || rule.indices != basis.multiIndices() || !same_germs()) {
    Eigen::MatrixXd nodes;
    projectionRule(basis, &nodes, &rule.weights);
    rule.psi = basis.evaluate(nodes);
    rule.germs = basis.germs();
    rule.order = basis.order();
    rule.indices = basis.multiIndices();
  }
  const Eigen::MatrixXd& psi = rule.psi;
  const Eigen::VectorXd& weights = rule.weights;
  // The parameters' values at the nodes (count x Q), then every model value.
  const Eigen::MatrixXd theta = parameter_coefficients * psi.transpose();
  const Eigen::MatrixXd values = rolloverValues(mapping, mapping.fullParameters(theta));
  if (!values.allFinite()) return out;
  out.names = rolloverQuantityNames();
  out.coefficients = values * weights.asDiagonal() * psi;  // projectValues
  return out;
}

}  // namespace pc_ekf
