#include "pc_ekf/filter/local_covariance.h"

#include "pc_ekf/filter/posterior_residual.h"
#include "pc_ekf/filter/prior_correction.h"
#include "pc_ekf/filter/trajectory_simulation.h"

namespace pc_ekf {

bool localCovariance(const PcPropagator& propagator, const MeasurementSeries& series,
                     const NoiseModel& noise, Eigen::MatrixXd& coefficients, long* simulations) {
  const ParameterMapping& mapping = propagator.mapping();
  const Eigen::Index n = mapping.count();
  const Eigen::MatrixXd prior = mapping.priorCoefficients(propagator.basis());
  const Eigen::VectorXd scale = priorScale(prior);
  constexpr double kStep = 1e-4;  // in prior std: well inside the model's smooth range
  const Eigen::VectorXd mean = coefficients.col(0);
  Eigen::MatrixXd theta = mean.replicate(1, 2 * n + 1);
  for (Eigen::Index i = 0; i < n; ++i) {
    theta(i, 1 + 2 * i) += kStep * scale[i];
    theta(i, 2 + 2 * i) -= kStep * scale[i];
  }
  for (Eigen::Index j = 0; j < theta.cols(); ++j) {
    for (Eigen::Index i = 0; i < n; ++i) {
      if (!(theta(i, j) >= mapping.lowerBound(static_cast<int>(i)) &&
            theta(i, j) <= mapping.upperBound(static_cast<int>(i)))) {
        return false;  // at the support's end: no two-sided difference
      }
    }
  }
  const auto channels = simulateChannels(propagator.model(), mapping.fullParameters(theta),
                                         sampleTimes(series), propagator.integration());
  if (simulations) *simulations += theta.cols();
  const Eigen::MatrixXd r = whitenedResiduals(series, noise, channels);
  if (!r.allFinite()) return false;
  Eigen::MatrixXd jacobian(r.rows(), n);  // whitened readings per prior std
  for (Eigen::Index i = 0; i < n; ++i) {
    jacobian.col(i) = (r.col(1 + 2 * i) - r.col(2 + 2 * i)) / (2.0 * kStep);
  }
  const Eigen::LLT<Eigen::MatrixXd> p0(scaledCovariance(prior, scale));
  if (p0.info() != Eigen::Success) return false;
  const Eigen::MatrixXd eye = Eigen::MatrixXd::Identity(n, n);
  const Eigen::LLT<Eigen::MatrixXd> information(jacobian.transpose() * jacobian + p0.solve(eye));
  if (information.info() != Eigen::Success) return false;
  return mapOntoMoments(coefficients, mean.cwiseQuotient(scale), information.solve(eye), scale);
}

}  // namespace pc_ekf
