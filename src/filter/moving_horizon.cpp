#include "pc_ekf/filter/moving_horizon.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "pc_ekf/pc/pc_statistics.h"

namespace pc_ekf {

bool MovingHorizon::carriesRollAngle(const std::vector<std::string>& channels) {
  const auto has = [&](const char* name) {
    return std::find(channels.begin(), channels.end(), name) != channels.end();
  };
  return has("accel_y") && has("accel_z") && has("gyro_x") && !has("gyro_y");
}

MovingHorizon::MovingHorizon(const PcPropagator& propagator, const MovingHorizonSettings& settings)
    : propagator_(propagator), settings_(settings) {
  const MechanicalModel& model = propagator_.model();
  if (model.dynamicStateSize() != 0) {
    throw std::invalid_argument(
        "filter.linearization: mean needs a model whose readings follow from its inputs "
        "(road.source: none); this model has " +
        std::to_string(model.dynamicStateSize()) + " dynamic states");
  }
  const int n = propagator_.parameterCount();
  parameters_ = n;
  const std::vector<std::string>& channels = model.channelNames();
  const auto index = [&](const char* name) {
    const auto it = std::find(channels.begin(), channels.end(), name);
    return it == channels.end() ? -1 : static_cast<int>(it - channels.begin());
  };
  accel_y_ = index("accel_y");
  accel_z_ = index("accel_z");
  gyro_ = index("gyro_x");
  angle_ = carriesRollAngle(channels) && model.readingCount() > 0;
  const Eigen::MatrixXd prior = propagator_.priorState().bottomRows(n);
  prior_mean_ = pcMean(prior);
  prior_std_ = pcStddev(prior);
  lower_.resize(n);
  upper_.resize(n);
  for (int i = 0; i < n; ++i) {
    lower_[i] = propagator_.mapping().lowerBound(i);
    upper_[i] = propagator_.mapping().upperBound(i);
    if (!(prior_std_[i] > 0.0)) {
      throw std::invalid_argument("filter.linearization: mean needs every uncertain parameter "
                                  "to have a spread");
    }
  }
  const auto& indices = propagator_.basis().multiIndices();
  degree_one_.assign(static_cast<std::size_t>(n), -1);
  for (std::size_t j = 0; j < indices.size(); ++j) {
    int total = 0, dim = -1;
    for (std::size_t d = 0; d < indices[j].size(); ++d) {
      total += indices[j][d];
      if (indices[j][d] == 1) dim = static_cast<int>(d);
    }
    if (total == 1 && dim >= 0 && dim < n) degree_one_[static_cast<std::size_t>(dim)] = static_cast<int>(j);
  }
  for (int d : degree_one_) {
    if (d < 0) throw std::invalid_argument("filter.linearization: mean needs pc.order >= 1");
  }
  reset();
}

void MovingHorizon::reset() {
  const int n = parameters_ + (angle_ ? 1 : 0);
  mean_ = Eigen::VectorXd::Zero(n);
  cov_ = Eigen::MatrixXd::Identity(n, n);
  if (angle_) cov_(last(), last()) = 0.0;  // at rest at t = 0: no angle integrated yet
  previous_time_ = 0.0;
  startWindow();
}

void MovingHorizon::walk(Eigen::MatrixXd& cov, double dt) const {
  if (!angle_ || !noise_ || !(dt > 0.0)) return;
  // The trapezoid's increment of the gyro's noise: variance (sigma dt)^2 / 2
  // per reading, each reading in two increments: (sigma dt)^2 a sample.
  const double sigma = noise_->channel_std.size() > gyro_ ? noise_->channel_std[gyro_] : 0.0;
  cov(last(), last()) += sigma * sigma * dt * dt;
}

void MovingHorizon::startWindow() {
  window_mean_ = mean_;
  window_cov_ = cov_;
  kept_.clear();
  window_start_ = -1.0;  // set by the window's first sample
}

bool MovingHorizon::predict(const Measurement& m, const NoiseModel& noise, const Eigen::VectorXd& at,
                            Eigen::VectorXd* values, Eigen::VectorXd* z0,
                            Eigen::MatrixXd* jacobian, Eigen::VectorXd* variances) {
  const MechanicalModel& model = propagator_.model();
  const int n = parameters_;
  const int c = static_cast<int>(m.channels.size());
  Eigen::MatrixXd zeta(n, n + 1);
  Eigen::VectorXd steps(n);
  for (int i = 0; i <= n; ++i) zeta.col(i) = at.head(n);
  for (int i = 0; i < n; ++i) {
    // A step inside the support (backwards near its upper end).
    double h = settings_.step;
    const double up = theta(at.head(n))[i] + h * prior_std_[i];
    if (!(up < upper_[i])) h = -h;
    steps[i] = h;
    zeta(i, i + 1) += h;
  }
  Eigen::MatrixXd th(n, n + 1);
  for (int i = 0; i <= n; ++i) th.col(i) = theta(zeta.col(i));
  const Eigen::MatrixXd full = propagator_.mapping().fullParameters(th);
  for (int i = 0; i <= n; ++i) {
    if (!model.invalidReason(full.col(i)).empty()) return false;
  }
  const std::unique_ptr<ModelBatch> batch = model.prepare(full);
  Eigen::ArrayXXd y = Eigen::ArrayXXd::Zero(model.stateSize(), n + 1);
  batch->readings(m.time, y);
  evaluations_ += n + 1;
  Eigen::MatrixXd z(c, n + 1);
  for (int r = 0; r < c; ++r) {
    z.row(r) = model.observationMatrix().row(m.channels[static_cast<std::size_t>(r)]) * y.matrix();
  }
  if (!z.allFinite()) return false;
  jacobian->resize(c, static_cast<Eigen::Index>(at.size()));
  for (int i = 0; i < n; ++i) jacobian->col(i) = (z.col(i + 1) - z.col(0)) / steps[i];
  *z0 = z.col(0);
  if (angle_) {
    // The angle the model used is the true one plus e: a reading's slope in
    // e is minus its slope in the angle, (g + a) (cos, -sin) of it, read off
    // the predicted accel_z and accel_y (rest: their zero added back).
    const bool rest = model.zero() == ZeroConvention::kRest;
    double ay = 0.0, az = 9.80665;
    for (int r = 0; r < c; ++r) {
      if (m.channels[static_cast<std::size_t>(r)] == accel_y_) ay = z(r, 0);
      if (m.channels[static_cast<std::size_t>(r)] == accel_z_) az = z(r, 0) + (rest ? 9.80665 : 0.0);
    }
    for (int r = 0; r < c; ++r) {
      const int ch = m.channels[static_cast<std::size_t>(r)];
      (*jacobian)(r, n) = ch == accel_y_ ? -az : ch == accel_z_ ? ay : 0.0;
    }
    // The prediction at `at` includes its angle error.
    *z0 += jacobian->col(n) * at[n];
  }
  const NoiseWhitening white(noise, m);
  *values = m.values;
  white.whiten(*values);
  white.whiten(*z0);
  white.whiten(*jacobian);
  *variances = white.variances();
  return true;
}

namespace {

// Kalman update of (mean, cov) by one whitened sample linearised at `at`:
// prediction z0 + J (mean - at). Joseph form keeps cov symmetric and PSD.
void linearUpdate(const Eigen::VectorXd& values, const Eigen::VectorXd& z0,
                  const Eigen::MatrixXd& j, const Eigen::VectorXd& r, const Eigen::VectorXd& at,
                  Eigen::VectorXd& mean, Eigen::MatrixXd& cov, UpdateDiagnostics* d) {
  const Eigen::VectorXd innovation = values - z0 - j * (mean - at);
  const Eigen::MatrixXd pj = cov * j.transpose();
  Eigen::MatrixXd s = j * pj;
  s.diagonal() += r;
  const Eigen::LLT<Eigen::MatrixXd> llt(s);
  if (llt.info() != Eigen::Success) {
    d->finite = false;
    d->singular = true;
    return;
  }
  const Eigen::MatrixXd k = llt.solve(pj.transpose()).transpose();
  d->innovation = innovation;
  d->nis = innovation.dot(llt.solve(innovation));
  d->channels = static_cast<int>(values.size());
  Eigen::MatrixXd ikh = Eigen::MatrixXd::Identity(mean.size(), mean.size()) - k * j;
  mean += k * innovation;
  cov = ikh * cov * ikh.transpose() + k * r.asDiagonal() * k.transpose();
  cov = 0.5 * (cov + cov.transpose());
  d->finite = mean.allFinite() && cov.allFinite() && std::isfinite(d->nis);
}

}  // namespace

HorizonStep MovingHorizon::propose(const Measurement& m, const NoiseModel& noise,
                                   Eigen::VectorXd* mean, Eigen::MatrixXd* cov) {
  noise_ = &noise;
  HorizonStep s;
  walk(cov_, m.time - previous_time_);
  *mean = mean_;
  *cov = cov_;
  if (m.channels.empty()) return s;
  Eigen::VectorXd values, z0, r;
  Eigen::MatrixXd j;
  if (!predict(m, noise, mean_, &values, &z0, &j, &r)) {
    s.update.finite = false;
    return s;
  }
  linearUpdate(values, z0, j, r, mean_, *mean, *cov, &s.update);
  return s;
}

void MovingHorizon::accept(const Measurement& m, HorizonStep& s, const Eigen::VectorXd& mean,
                           const Eigen::MatrixXd& cov, bool damp) {
  if (window_start_ < 0.0) window_start_ = m.time;
  const double dt = m.time - previous_time_;
  previous_time_ = m.time;
  const bool used = s.update.finite && !s.gated && !m.channels.empty();
  if (used) {
    if (damp) {
      s.damping = supportDamping(theta(mean_.head(parameters_)), theta(mean.head(parameters_)),
                                 lower_, upper_);
    }
    mean_ += s.damping * (mean - mean_);
    cov_ += s.damping * (cov - cov_);
  }
  kept_.push_back({m, dt, mean_, used});
  if (settings_.window > 0.0 && m.time - window_start_ >= settings_.window) endWindow(s);
}

void MovingHorizon::endWindow(HorizonStep& s) {
  for (int pass = 0; pass < settings_.reruns && noise_; ++pass) {
    double furthest = 0.0;
    const Eigen::ArrayXd sd = cov_.diagonal().cwiseMax(0.0).cwiseSqrt().array();
    for (const Kept& k : kept_) {
      if (!k.used) continue;
      const Eigen::ArrayXd away = (k.linearised_at - mean_).head(parameters_).array().abs();
      furthest = std::max(furthest, (away / sd.head(parameters_)).maxCoeff());
    }
    if (!(furthest > settings_.shift)) break;
    // Every used sample of the window linearised at the window's mean, from
    // the window's prior (one Gauss-Newton step on the window).
    const Eigen::VectorXd at = mean_;
    Eigen::VectorXd mean = window_mean_;
    Eigen::MatrixXd cov = window_cov_;
    bool ok = true;
    for (Kept& k : kept_) {
      walk(cov, k.dt);
      if (!k.used) continue;
      Eigen::VectorXd values, z0, r;
      Eigen::MatrixXd j;
      UpdateDiagnostics d;
      if (!predict(k.m, *noise_, at, &values, &z0, &j, &r)) {
        ok = false;
        break;
      }
      linearUpdate(values, z0, j, r, at, mean, cov, &d);
      if (!d.finite) {
        ok = false;
        break;
      }
      k.linearised_at = at;
    }
    if (!ok) break;
    const double gamma = supportDamping(theta(window_mean_.head(parameters_)),
                                        theta(mean.head(parameters_)), lower_, upper_);
    mean_ = window_mean_ + gamma * (mean - window_mean_);
    cov_ = window_cov_ + gamma * (cov - window_cov_);
    ++s.reruns;
  }
  startWindow();
}

Eigen::MatrixXd MovingHorizon::coefficients() const {
  const int n = parameters_;
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(n, propagator_.basis().size());
  c.col(0) = theta(mean_.head(n));
  Eigen::LDLT<Eigen::MatrixXd> ldlt(cov_.topLeftCorner(n, n));
  // A square root L L^T = cov (LDLT with pivoting tolerates a singular cov).
  Eigen::MatrixXd l = ldlt.transpositionsP().transpose() * Eigen::MatrixXd(ldlt.matrixL()) *
                      ldlt.vectorD().cwiseMax(0.0).cwiseSqrt().asDiagonal();
  const Eigen::MatrixXd scaled = prior_std_.asDiagonal() * l;
  for (int j = 0; j < n; ++j) c.col(degree_one_[static_cast<std::size_t>(j)]) = scaled.col(j);
  return c;
}

void MovingHorizon::restore(const Eigen::MatrixXd& coefficients) {
  const int n = parameters_;
  if (coefficients.rows() != n) throw std::invalid_argument("moving horizon: wrong parameter count");
  const Eigen::MatrixXd higher =
      prior_std_.cwiseInverse().asDiagonal() * coefficients.rightCols(coefficients.cols() - 1);
  // The angle's error is not in a checkpoint: it restarts where it was.
  const Eigen::MatrixXd angle_cov = angle_ ? cov_.bottomRightCorner(1, 1) : Eigen::MatrixXd();
  const double angle_mean = angle_ ? mean_[last()] : 0.0;
  mean_.head(n) = (pcMean(coefficients) - prior_mean_).cwiseQuotient(prior_std_);
  cov_.setZero();
  cov_.topLeftCorner(n, n) = higher * higher.transpose();
  if (angle_) {
    mean_[last()] = angle_mean;
    cov_(last(), last()) = angle_cov(0, 0);
  }
  startWindow();
}

void MovingHorizon::reopen(const std::vector<int>& rows) {
  for (int r : rows) {
    mean_[r] = 0.0;
    cov_.row(r).setZero();
    cov_.col(r).setZero();
    cov_(r, r) = 1.0;
  }
  startWindow();
}

void MovingHorizon::drift(const Eigen::VectorXd& intensity, double dt) {
  if (intensity.size() != parameters_ || !(dt > 0.0)) return;
  cov_.diagonal().head(parameters_).array() +=
      (intensity.cwiseQuotient(prior_std_)).array().square() * dt;
}

}  // namespace pc_ekf
