// Total Sobol indices of the model's readings over a record, from whole-record
// simulations (docs/method.md §3.7). The filters' forecast re-projects the
// state on the basis at every sample, and its leave-one-out error measures one
// step's truncation only; a velocity reading late in a record is a phase of
// the motion, far from quadratic in the load and the inertia (vehicle_live.yaml
// at order 2: a quarter of the velocities' variance missed). Here each design
// point is simulated over the whole record, the readings at every sample are
// fitted by least squares on a basis that leave-one-out error chooses, and the
// indices are read off that fit.
//
// The bases tried: total degree 2 in every germ; then, with the germs ranked
// by their largest total index at degree 2, for each count k of leading germs
// and each lead order p: every term of degree <= p in the leading germs alone,
// and terms with other germs of degree <= other_degree in those germs and
// <= mixed_order in all. A few germs usually carry the nonlinearity (the load
// and the roll inertia); the others act nearly additively.
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <vector>

#include "pc_ekf/sensitivity/prior_sensitivity.h"
#include "pc_ekf/filter/uncertain_parameters.h"
#include "pc_ekf/model/integrator.h"
#include "pc_ekf/model/mechanical_model.h"

namespace pc_ekf {

struct SimulatedSensitivitySettings {
  std::vector<int> lead_counts{3, 4, 5};  // k: leading germs (capped at the dimension)
  std::vector<int> lead_orders{4, 6};     // p: degree among the leading germs
  int mixed_order = 3;                    // degree of a term with another germ
  int other_degree = 2;                   // the other germs' degree in a term
  double points_per_term = 3.0;           // Q = this x S for every basis tried
  // Bases of more terms are not tried (their least squares grows as Q S^2:
  // at n = 15 the largest tried has 1002; at n = 30 the lead bases would
  // reach thousands).
  int max_terms = 1500;
  std::uint64_t seed = 1;                 // the scrambled Halton points'
  // A longer record is read at this many evenly spaced samples: the indices
  // are variance-weighted over the record, and the fit's cost grows with the
  // readings it fits (a 10 s drive at 200 Hz: 14 000 readings per point).
  int max_samples = 200;
  int threads = 0;                        // simulation threads; 0 = the machine's cores
};

// The readings of `channels` at `times` for the germ points xi (count x B):
// (channels x times) x B, row c * times + k for channel c at sample k;
// columns whose parameters are inadmissible are NaN (simulateGermChannels).
Eigen::MatrixXd recordReadings(const MechanicalModel& model, const ParameterMapping& mapping,
                               const Eigen::MatrixXd& xi, const std::vector<double>& times,
                               const std::vector<int>& channels,
                               const IntegratorSettings& integration, int threads,
                               long* simulations = nullptr);

// The multi-indices of one such basis (graded: the total-degree order of
// polynomial_basis.h, filtered). `leading`: germ indices.
std::vector<std::vector<int>> leadingGermIndices(int dimension, const std::vector<int>& leading,
                                                 int lead_order, int mixed_order,
                                                 int other_degree);

// `channels`: model channel indices; `times`: increasing sample times (> 0).
// The result's `unexplained` is the chosen fit's leave-one-out share of each
// channel's variance, `expansion` says which basis on how many points.
// Throws std::runtime_error when a design point's simulation fails.
PriorSensitivity simulatedSensitivity(const MechanicalModel& model, const ParameterMapping& mapping,
                                      const std::vector<double>& times,
                                      const std::vector<int>& channels,
                                      const IntegratorSettings& integration,
                                      const SimulatedSensitivitySettings& settings = {});

}  // namespace pc_ekf
