// The rollover outputs (docs/models.md, "Rollover outputs"): the loaded
// vehicle's centre-of-mass height, static stability factor and static
// rollover threshold, each a PC expansion of the germs, projected from the
// parameters' expansions and the model's fixed values.
#pragma once

#include <Eigen/Dense>
#include <string>
#include <vector>

#include "pc_ekf/filter/uncertain_parameters.h"
#include "pc_ekf/pc/polynomial_basis.h"

namespace pc_ekf {

// PC expansions of quantities derived from the parameters.
struct DerivedExpansions {
  std::vector<std::string> names;
  Eigen::MatrixXd coefficients;  // names x S (term 0: the mean); empty: none
  bool empty() const { return names.empty(); }
};

// cg_height, static_stability_factor, rollover_threshold (in this order).
const std::vector<std::string>& rolloverQuantityNames();

// True when the model has heights (the roll plane's or the full car's) and
// mount_height's configured value is > 0: without heights there is no CG
// height.
bool hasRolloverQuantities(const ParameterMapping& mapping);

// The quantities at full parameter vectors (model parameters x Q, the
// model's order): 3 x Q. Requires hasRolloverQuantities(mapping).
//   cg_height = ((m + M) h_P + m h_b + M h_M + sum m_u r_w) / (m + M + sum m_u)
//   static_stability_factor = track / (2 cg_height), rollover_threshold = g SSF,
// m the body's mass, track = L (roll plane) or w (full car), the sum over
// every wheel (the full car's four).
Eigen::MatrixXd rolloverValues(const ParameterMapping& mapping, const Eigen::MatrixXd& full);

// The germ rule the projection uses: tensor Gauss with order + 4 nodes per
// dimension while that is at most 20 000 nodes, else Smolyak of level
// order + 1 (exact to total degree 2 order + 3: a quantity linear in the
// parameters times a basis term; the quantities are nearly so, and level
// order + 2 moved cg_height's mean and std by 1e-11 relative on a 20-germ
// road-free posterior at ten times the nodes).
void projectionRule(const PolynomialBasis& basis, Eigen::MatrixXd* nodes, Eigen::VectorXd* weights);

// Coefficients (rows of `values` x S) of the projection c_j = E[f psi_j] by
// the rule (nodes Q x dimension, weights Q); values: quantities x Q at the nodes.
Eigen::MatrixXd projectValues(const PolynomialBasis& basis, const Eigen::MatrixXd& nodes,
                              const Eigen::VectorXd& weights, const Eigen::MatrixXd& values);

// Starts making the rule of `basis` in the background (a sparse grid over
// many germs takes milliseconds), for rolloverExpansions to find made; nothing
// without heights.
void prepareRolloverRule(const ParameterMapping& mapping, const PolynomialBasis& basis);

// The rollover expansions of parameters whose expansions are
// `parameter_coefficients` (mapping.count() x basis.size()): the quantities
// at the parameters' values at projectionRule's nodes, projected. Empty when
// !hasRolloverQuantities, the coefficients are empty or not finite.
// threads > 1: the rule's blocks of nodes split between two threads (the
// blocks' sums still added in order: the same numbers).
DerivedExpansions rolloverExpansions(const ParameterMapping& mapping, const PolynomialBasis& basis,
                                     const Eigen::MatrixXd& parameter_coefficients,
                                     int threads = 1);

}  // namespace pc_ekf
