#include "pc_ekf/filter/ensemble_kalman_filter.h"

#include <cmath>
#include <stdexcept>

#include "pc_ekf/filter/kalman_update.h"
#include "pc_ekf/filter/one_step_filter.h"
#include "pc_ekf/pc/polynomial_basis.h"
#include "pc_ekf/pc/in_parts.h"
#include "pc_ekf/pc/pc_statistics.h"

namespace pc_ekf {

EnsembleKalmanFilter::EnsembleKalmanFilter(std::shared_ptr<const MechanicalModel> model,
                                           ParameterMapping mapping, const EnkfSettings& settings)
    : model_(std::move(model)), mapping_(std::move(mapping)), settings_(settings), rng_(settings.seed) {
  if (settings.members < EnkfEnsemble::kMinMembers) {
    throw std::invalid_argument("EnKF needs at least " + std::to_string(EnkfEnsemble::kMinMembers) +
                                " members");
  }
  const PolynomialBasis basis(mapping_.germs(), 0);
  theta_ = mapping_.valuesAtGerms(sampleGerms(basis, settings.members, settings.seed));
  const Eigen::MatrixXd full = mapping_.fullParameters(theta_);
  admissible_.assign(settings.members, true);
  for (int e = 0; e < settings.members; ++e) admissible_[e] = model_->invalidReason(full.col(e)).empty();
  Eigen::MatrixXd valid = full;
  for (int e = 0; e < settings.members; ++e) {
    if (!admissible_[e]) valid.col(e) = model_->nominalParameters();
  }
  states_ = model_->prepare(valid)->initialState();
}

void EnsembleKalmanFilter::forecast(double t1, int* inadmissible) {
  if (t1 == t_) return;
  const Eigen::MatrixXd full = mapping_.fullParameters(theta_);
  std::vector<Eigen::Index> cols;
  for (Eigen::Index e = 0; e < full.cols(); ++e) {
    admissible_[e] = model_->invalidReason(full.col(e)).empty() && states_.col(e).allFinite();
    if (admissible_[e]) cols.push_back(e);
  }
  *inadmissible = static_cast<int>(full.cols() - cols.size());
  const Eigen::Index n = static_cast<Eigen::Index>(cols.size());
  const int threads = n >= 64 ? std::max(1, settings_.threads) : 1;
  // Contiguous parts of the admissible members, each integrated as one batch
  // and written back to its own columns.
  inNumberedParts(static_cast<int>(n), threads, [&](int, int b, int e) {
    if (e == b) return;
    Eigen::MatrixXd p(full.rows(), e - b);
    Eigen::ArrayXXd part(states_.rows(), e - b);
    for (Eigen::Index i = b; i < e; ++i) {
      p.col(i - b) = full.col(cols[i]);
      part.col(i - b) = states_.col(cols[i]);
    }
    const auto batch = model_->prepare(p);
    integrate(*model_, *batch, t_, t1, part, settings_.integration);
    for (Eigen::Index i = b; i < e; ++i) states_.col(cols[i]) = part.col(i - b);
  });
  integrations_ += n;
}

EnkfStep EnsembleKalmanFilter::process(const Measurement& m) {
  const std::string problem = measurementProblem(m, static_cast<int>(model_->channelNames().size()));
  if (!problem.empty()) throw std::invalid_argument("measurement rejected: " + problem);
  if (m.time < t_) throw std::invalid_argument("measurement rejected: time before the filter's");
  EnkfStep s;
  forecast(m.time, &s.inadmissible_members);
  t_ = m.time;
  s.index = ++samples_;
  s.time = m.time;

  std::vector<Eigen::Index> cols;
  for (Eigen::Index e = 0; e < theta_.cols(); ++e) {
    if (admissible_[e] && states_.col(e).allFinite()) cols.push_back(e);
  }
  const Eigen::Index ne = static_cast<Eigen::Index>(cols.size()), k = m.values.size();
  const int ns = model_->stateSize(), np = mapping_.count();
  if (ne >= 2 && k > 0) {
    Eigen::MatrixXd x(ns + np, ne), h(k, ns);
    for (Eigen::Index i = 0; i < ne; ++i) {
      x.col(i) << states_.col(cols[i]).matrix(), theta_.col(cols[i]);
    }
    for (Eigen::Index c = 0; c < k; ++c) h.row(c) = model_->observationMatrix().row(m.channels[c]);
    Eigen::MatrixXd hx = h * x.topRows(ns);
    // Noise correlated between channels: the update on whitened readings.
    const NoiseWhitening white(settings_.noise, m);
    Eigen::VectorXd z = m.values;
    white.whiten(hx);
    white.whiten(z);
    const Eigen::VectorXd& r = white.variances();
    const Eigen::VectorXd xm = x.rowwise().mean(), zm = hx.rowwise().mean();
    const Eigen::MatrixXd a = x.colwise() - xm, y = hx.colwise() - zm;
    const double scale = std::sqrt(double(ne - 1));
    if (settings_.square_root) {
      // Mean and scaled anomalies play the role of PC coefficients.
      Eigen::MatrixXd w(ns + np, ne + 1);
      w << xm, a / scale;
      Eigen::MatrixXd wz(k, ne + 1);
      wz << zm, y / scale;
      const UpdateDiagnostics d = pcKalmanUpdate(w, wz, z, r, UpdateRule::kSquareRoot);
      s.innovation = d.innovation;
      s.nis = d.nis;
      x = (w.rightCols(ne) * scale).colwise() + w.col(0);
    } else {
      const Eigen::MatrixXd pzz =
          y * y.transpose() / double(ne - 1) + Eigen::MatrixXd(r.asDiagonal());
      const Eigen::LDLT<Eigen::MatrixXd> ldlt(pzz);
      const Eigen::MatrixXd gain = ldlt.solve(y * a.transpose() / double(ne - 1)).transpose();
      s.innovation = z - zm;
      s.nis = s.innovation.dot(ldlt.solve(s.innovation));
      std::normal_distribution<double> normal;
      const Eigen::VectorXd sd = r.cwiseSqrt();
      for (Eigen::Index i = 0; i < ne; ++i) {
        Eigen::VectorXd perturbed = z;
        for (Eigen::Index c = 0; c < k; ++c) perturbed[c] += sd[c] * normal(rng_);
        x.col(i) += gain * (perturbed - hx.col(i));
      }
    }
    for (Eigen::Index i = 0; i < ne; ++i) {
      states_.col(cols[i]) = x.col(i).head(ns).array();
      theta_.col(cols[i]) = x.col(i).tail(np);
    }
  }
  Eigen::MatrixXd valid(np, ne);
  for (Eigen::Index i = 0; i < ne; ++i) valid.col(i) = theta_.col(cols[i]);
  s.mean = valid.rowwise().mean();
  s.stddev = Eigen::VectorXd::Zero(np);
  if (ne >= 2) {
    s.stddev = ((valid.colwise() - s.mean).rowwise().squaredNorm() / double(ne - 1)).cwiseSqrt();
  }
  s.finite = s.mean.allFinite() && s.stddev.allFinite();
  return s;
}

}  // namespace pc_ekf
