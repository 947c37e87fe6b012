// A batch method's covariance from the model's local information at its mean
// (filter.es_mda.covariance: local, docs/method.md §4.5). On a curved ridge
// of the posterior (many tolerances that trade off with the load) the passes'
// surrogate spans a working prior wider than the ridge's local bend, and the
// linear updates read that bend as information: ES-MDA's std came out 0.68-0.96
// of the exact posterior's at n = 15 while its mean was within 0.3 std. The
// Gauss-Newton information of the exact model at that mean, J^T R^-1 J, plus
// the prior's (as Gaussian as every update here takes it), gives
// 0.85-1.15 on the same records (docs/studies/real_vehicle_reference.md §5).
#pragma once

#include <Eigen/Dense>

#include "pc_ekf/filter/measurement.h"
#include "pc_ekf/filter/pc_propagator.h"

namespace pc_ekf {

// coefficients: the parameters' expansion (parameters x S) whose mean stays;
// its covariance becomes (J^T R^-1 J + P0^-1)^-1, J by central differences of
// the whitened readings over the whole record (2 n + 1 model runs; step 1e-4
// prior std), P0 the prior's covariance. The expansion is mapped affinely
// (its shape kept). False, coefficients unchanged, when a run fails or a
// matrix is not positive definite. *simulations: the runs, when given.
bool localCovariance(const PcPropagator& propagator, const MeasurementSeries& series,
                     const NoiseModel& noise, Eigen::MatrixXd& coefficients,
                     long* simulations = nullptr);

// The posterior's mode near `start` (parameters): up to max_steps Gauss-Newton
// steps on 1/2 |r|^2 + the Gaussian prior's term, each halved until the
// density rises (2 n + 1 runs for a step's Jacobian, one per trial). Where
// the posterior is a curved ridge its mean lies off the ridge and fits the
// readings worse than noise allows; the posterior-predictive check's
// chi-square (dof = readings - n) is the residual's at the best fit.
// Returns start when no step improves.
Eigen::VectorXd posteriorMode(const PcPropagator& propagator, const MeasurementSeries& series,
                              const NoiseModel& noise, const Eigen::VectorXd& start,
                              int max_steps = 5, long* simulations = nullptr);

}  // namespace pc_ekf
