#include "pc_ekf/filter/local_covariance.h"

#include "pc_ekf/filter/posterior_residual.h"
#include "pc_ekf/filter/prior_correction.h"
#include "pc_ekf/filter/trajectory_simulation.h"

namespace pc_ekf {
namespace {

constexpr double kStep = 1e-4;  // in prior std: well inside the model's smooth range

// The posterior's negative log density near theta, in units of the prior's
// std (posterior_mode_search.h's linearise works in germ units with the
// exact prior density and forward differences; here the prior is taken by its
// variance, as the updates take it, and the differences are central): 1/2 |r|^2 + 1/2 (x - m0)^T P0^-1 (x - m0), with the whitened readings'
// residuals r and their Jacobian by central differences (2 n + 1 runs).
struct LocalLinearisation {
  bool ok = false;
  Eigen::VectorXd residual;   // r at theta
  Eigen::MatrixXd jacobian;   // dr / dx, x = theta / scale
  Eigen::MatrixXd prior_information;
  Eigen::VectorXd prior_mean;  // x units
};

bool inSupport(const ParameterMapping& mapping, const Eigen::MatrixXd& theta) {
  for (Eigen::Index j = 0; j < theta.cols(); ++j) {
    for (Eigen::Index i = 0; i < theta.rows(); ++i) {
      if (!(theta(i, j) >= mapping.lowerBound(static_cast<int>(i)) &&
            theta(i, j) <= mapping.upperBound(static_cast<int>(i)))) {
        return false;
      }
    }
  }
  return true;
}

// Whitened residuals at the columns of theta; empty when a column leaves the
// support or a run fails.
Eigen::MatrixXd residualsAt(const PcPropagator& propagator, const MeasurementSeries& series,
                            const NoiseModel& noise, const Eigen::MatrixXd& theta, long* simulations) {
  const ParameterMapping& mapping = propagator.mapping();
  if (!inSupport(mapping, theta)) return {};
  const auto channels = simulateChannels(propagator.model(), mapping.fullParameters(theta),
                                         sampleTimes(series), propagator.integration());
  if (simulations) *simulations += theta.cols();
  Eigen::MatrixXd r = whitenedResiduals(series, noise, channels);
  return r.allFinite() ? r : Eigen::MatrixXd();
}

LocalLinearisation lineariseAt(const PcPropagator& propagator, const MeasurementSeries& series,
                        const NoiseModel& noise, const Eigen::VectorXd& theta,
                        const Eigen::VectorXd& scale, long* simulations) {
  const ParameterMapping& mapping = propagator.mapping();
  const Eigen::Index n = mapping.count();
  LocalLinearisation l;
  Eigen::MatrixXd points = theta.replicate(1, 2 * n + 1);
  for (Eigen::Index i = 0; i < n; ++i) {
    points(i, 1 + 2 * i) += kStep * scale[i];
    points(i, 2 + 2 * i) -= kStep * scale[i];
  }
  const Eigen::MatrixXd r = residualsAt(propagator, series, noise, points, simulations);
  if (r.size() == 0) return l;  // at the support's end, or a run failed
  l.residual = r.col(0);
  l.jacobian.resize(r.rows(), n);
  for (Eigen::Index i = 0; i < n; ++i) {
    l.jacobian.col(i) = (r.col(1 + 2 * i) - r.col(2 + 2 * i)) / (2.0 * kStep);
  }
  const Eigen::MatrixXd prior = mapping.priorCoefficients(propagator.basis());
  const Eigen::LLT<Eigen::MatrixXd> p0(scaledCovariance(prior, scale));
  if (p0.info() != Eigen::Success) return l;
  l.prior_information = p0.solve(Eigen::MatrixXd::Identity(n, n));
  l.prior_mean = prior.col(0).cwiseQuotient(scale);
  l.ok = true;
  return l;
}

double objective(const Eigen::VectorXd& r, const Eigen::VectorXd& x, const LocalLinearisation& l) {
  const Eigen::VectorXd d = x - l.prior_mean;
  return 0.5 * r.squaredNorm() + 0.5 * d.dot(l.prior_information * d);
}

}  // namespace

bool localCovariance(const PcPropagator& propagator, const MeasurementSeries& series,
                     const NoiseModel& noise, Eigen::MatrixXd& coefficients, long* simulations) {
  const ParameterMapping& mapping = propagator.mapping();
  const Eigen::VectorXd scale = priorScale(mapping.priorCoefficients(propagator.basis()));
  const Eigen::VectorXd mean = coefficients.col(0);
  const LocalLinearisation l = lineariseAt(propagator, series, noise, mean, scale, simulations);
  if (!l.ok) return false;
  const Eigen::Index n = mean.size();
  const Eigen::LLT<Eigen::MatrixXd> information(l.jacobian.transpose() * l.jacobian +
                                                l.prior_information);
  if (information.info() != Eigen::Success) return false;
  return mapOntoMoments(coefficients, mean.cwiseQuotient(scale),
                        information.solve(Eigen::MatrixXd::Identity(n, n)), scale);
}

Eigen::VectorXd posteriorMode(const PcPropagator& propagator, const MeasurementSeries& series,
                              const NoiseModel& noise, const Eigen::VectorXd& start, int max_steps,
                              long* simulations) {
  const ParameterMapping& mapping = propagator.mapping();
  const Eigen::VectorXd scale = priorScale(mapping.priorCoefficients(propagator.basis()));
  Eigen::VectorXd theta = start;
  for (int step = 0; step < max_steps; ++step) {
    const LocalLinearisation l = lineariseAt(propagator, series, noise, theta, scale, simulations);
    if (!l.ok) break;
    const Eigen::VectorXd x = theta.cwiseQuotient(scale);
    const double before = objective(l.residual, x, l);
    const Eigen::MatrixXd h = l.jacobian.transpose() * l.jacobian + l.prior_information;
    const Eigen::VectorXd g =
        l.jacobian.transpose() * l.residual + l.prior_information * (x - l.prior_mean);
    Eigen::VectorXd dx = -h.ldlt().solve(g);
    if (!dx.allFinite()) break;
    // Halve the step until the posterior density rises (the readings are not
    // linear over a whole step along a curved ridge).
    bool improved = false;
    for (int halving = 0; halving < 6 && !improved; ++halving, dx *= 0.5) {
      const Eigen::VectorXd next = (x + dx).cwiseProduct(scale);
      const Eigen::MatrixXd r = residualsAt(propagator, series, noise, next, simulations);
      if (r.size() == 0) continue;
      const double after = objective(r.col(0), x + dx, l);
      if (after < before) {
        improved = true;
        theta = next;
        if (before - after < 1e-6 * (1.0 + before)) return theta;  // converged
      }
    }
    if (!improved) break;
  }
  return theta;
}

}  // namespace pc_ekf
