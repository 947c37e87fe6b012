#include "pc_ekf/filter/batch_update.h"

#include <algorithm>
#include <stdexcept>

#include "pc_ekf/filter/local_covariance.h"
#include "pc_ekf/filter/prior_correction.h"
#include "pc_ekf/filter/trajectory_simulation.h"
#include "pc_ekf/pc/pc_statistics.h"

namespace pc_ekf {

StackedObservations forecastRecord(const PcPropagator& propagator,
                                   const Eigen::MatrixXd& theta_coeffs,
                                   const MeasurementSeries& series, const NoiseModel& noise,
                                   ForecastReport* report, const Eigen::MatrixXd* nuisance_u,
                                   const Eigen::VectorXd* nuisance_std) {
  const int q = propagator.design().pointCount();
  report->points = q;
  std::vector<std::string> reasons;
  const Eigen::MatrixXd params = propagator.parametersAtPoints(theta_coeffs, &reasons);
  std::vector<bool> usable(q, true);
  std::vector<Eigen::Index> cols;
  for (int i = 0; i < q; ++i) {
    if (reasons[i].empty()) {
      cols.push_back(i);
    } else {
      usable[i] = false;
      ++report->invalid_points;
      if (report->first_problem.empty()) report->first_problem = reasons[i];
    }
  }
  Eigen::MatrixXd valid(params.rows(), cols.size());
  for (std::size_t i = 0; i < cols.size(); ++i) valid.col(i) = params.col(cols[i]);
  const auto channels =
      simulateChannels(propagator.model(), valid, sampleTimes(series), propagator.integration());

  Eigen::Index rows = 0;
  for (const auto& m : series) rows += static_cast<Eigen::Index>(m.channels.size());
  Eigen::MatrixXd values = Eigen::MatrixXd::Zero(rows, q);
  StackedObservations out;
  out.z.resize(rows);
  Eigen::Index row = 0;
  for (std::size_t k = 0; k < series.size(); ++k) {
    const Measurement& m = series[k];
    for (std::size_t c = 0; c < m.channels.size(); ++c, ++row) {
      out.z[row] = m.values[c];
      for (std::size_t i = 0; i < cols.size(); ++i) values(row, cols[i]) = channels[k](m.channels[c], i);
    }
  }
  for (std::size_t i = 0; i < cols.size(); ++i) {
    if (!values.col(cols[i]).allFinite()) {
      usable[cols[i]] = false;
      ++report->nonfinite_points;
      values.col(cols[i]).setZero();
    }
  }
  out.z_coeffs = propagator.project(values, usable, report);
  out.variances.resize(rows);
  const bool nuisance = nuisance_u && nuisance_u->cols() > 0 && nuisance_u->rows() == rows;
  Eigen::MatrixXd u = nuisance ? *nuisance_u : Eigen::MatrixXd();
  row = 0;
  for (const Measurement& m : series) {
    const Eigen::Index k = m.values.size();
    const NoiseWhitening white(noise, m);
    white.whiten(out.z.segment(row, k));
    white.whiten(out.z_coeffs.middleRows(row, k));
    if (nuisance) white.whiten(u.middleRows(row, k));
    out.variances.segment(row, k) = white.variances();
    row += k;
  }
  if (nuisance) {
    // In units of each row's std, where the noise is I + U P U^T; W makes it I.
    const Eigen::VectorXd sd = out.variances.cwiseSqrt();
    const Eigen::VectorXd inv = sd.cwiseInverse();
    u = inv.asDiagonal() * u;
    const NuisanceWhitening w(u, *nuisance_std);
    out.z = out.z.cwiseProduct(inv);
    w.apply(Eigen::Ref<Eigen::VectorXd>(out.z));
    out.z = out.z.cwiseProduct(sd);
    out.z_coeffs = inv.asDiagonal() * out.z_coeffs;
    w.apply(Eigen::Ref<Eigen::MatrixXd>(out.z_coeffs));
    out.z_coeffs = sd.asDiagonal() * out.z_coeffs;
  }
  return out;
}

BatchResult batchUpdate(const PcPropagator& propagator, const MeasurementSeries& series,
                        const NoiseModel& noise, UpdateRule rule,
                        const std::vector<double>& alphas, SupportRule support,
                        const Eigen::MatrixXd& start, const BatchNuisance& nuisance) {
  if (alphas.empty()) throw std::invalid_argument("batchUpdate: no iterations");
  BatchResult result;
  Eigen::MatrixXd theta =
      start.size() > 0 ? start : propagator.priorState().bottomRows(propagator.parameterCount());
  for (std::size_t i = 0; i < alphas.size(); ++i) {
    ForecastReport report;
    Eigen::MatrixXd u;
    Eigen::VectorXd u_std;
    if (nuisance.active()) {
      const Eigen::VectorXd at = pcMean(theta);
      u = nuisanceSensitivity(propagator.model(), propagator.mapping().fullParameters(at), series,
                              propagator.integration(), nuisance, &u_std);
    }
    const StackedObservations obs =
        forecastRecord(propagator, theta, series, noise, &report, &u, &u_std);
    result.forecast.merge(report);
    result.observations = static_cast<int>(obs.z.size());
    if (!report.ok) {
      result.finite = false;
      break;
    }
    const Eigen::VectorXd r = alphas[i] * obs.variances;
    const Eigen::MatrixXd before = theta;
    const UpdateDiagnostics d = pcKalmanUpdate(theta, obs.z_coeffs, obs.z, r, rule);
    if (support == SupportRule::kDamp && d.finite) {
      const ParameterMapping& map = propagator.mapping();
      Eigen::VectorXd lower(map.count()), upper(map.count());
      for (int p = 0; p < map.count(); ++p) {
        lower[p] = map.lowerBound(p);
        upper[p] = map.upperBound(p);
      }
      const double gamma = supportDamping(before.col(0), theta.col(0), lower, upper);
      if (gamma < 1.0) theta = before + gamma * (theta - before);
      result.damping = std::min(result.damping, gamma);
    }
    if (i == 0) result.nis = d.nis;
    result.iterations = static_cast<int>(i + 1);
    if (!d.finite) {
      result.finite = false;
      break;
    }
  }
  result.coefficients = theta;
  result.mean = pcMean(theta);
  result.stddev = pcStddev(theta);
  result.finite = result.finite && theta.allFinite();
  return result;
}

BatchResult batchUpdateRestarted(const PcPropagator& propagator, const MeasurementSeries& series,
                                 const NoiseModel& noise, UpdateRule rule,
                                 const std::vector<double>& alphas, SupportRule support,
                                 const BatchRestarts& restarts) {
  if (restarts.restarts < 0 || !(restarts.width > BatchRestarts::kMinWidth)) {
    throw std::invalid_argument("batchUpdateRestarted: need restarts >= 0 and width > 1");
  }
  BatchResult result =
      batchUpdate(propagator, series, noise, rule, alphas, support, Eigen::MatrixXd(),
                  restarts.nuisance);
  const Eigen::MatrixXd prior = propagator.mapping().priorCoefficients(propagator.basis());
  const Eigen::VectorXd prior_std = pcStddev(prior);
  for (int k = 0; k < restarts.restarts && result.finite && result.forecast.ok; ++k) {
    const ParameterMapping& map = propagator.mapping();
    Eigen::MatrixXd working =
        map.workingCoefficients(propagator.basis(), result.mean, restarts.width * result.stddev,
                                true);
    for (int i = 0; i < working.rows(); ++i) {
      // Not narrowed, or cut short by a support narrower than the working prior
      // (P_q^-1 - Q^-1 would be a difference of nearly equal numbers): the
      // prior stays. Near the support's end the working prior moves inwards.
      const double asked = restarts.width * result.stddev[i];
      if (asked >= prior_std[i] || pcStddev(working.row(i))[0] < 0.75 * asked) {
        working.row(i) = prior.row(i);
      }
    }
    BatchResult next =
        batchUpdate(propagator, series, noise, rule, alphas, support, working, restarts.nuisance);
    if (!next.finite || !next.forecast.ok ||
        !correctForPrior(prior, working, next.coefficients)) {
      break;  // the last good result stands
    }
    next.mean = pcMean(next.coefficients);
    next.stddev = pcStddev(next.coefficients);
    next.forecast.merge(result.forecast);
    next.iterations += result.iterations;
    next.nis = result.nis;  // the prior predictive's
    // next.damping: the last run's. The first run's linearisation spans the
    // prior, where a step towards the support's end need not be a model
    // error; a restart that still meets the end is.
    result = std::move(next);
  }
  if (restarts.local_covariance && result.finite && result.forecast.ok &&
      localCovariance(propagator, series, noise, result.coefficients)) {
    result.mean = pcMean(result.coefficients);
    result.stddev = pcStddev(result.coefficients);
    result.local_covariance = true;
    result.mode = posteriorMode(propagator, series, noise, result.mean);
  }
  return result;
}

}  // namespace pc_ekf
