#include "pc_ekf/filter/moving_horizon.h"

#include <algorithm>
#include <cmath>
#include <future>
#include <limits>
#include <stdexcept>

#include "pc_ekf/filter/small_product.h"
#include "pc_ekf/pc/pc_statistics.h"

namespace pc_ekf {

namespace {
// g for the cross-fall's lateral share g sin(beta) (the models' default gravity).
constexpr double kCrossFallGravity = 9.81;
}  // namespace

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
  // The mass scale: masses, stiffnesses, damper rates and inertias (units of
  // kg or N) times one factor change no reading, so the data say nothing
  // along it; its direction at the prior's mean, in zeta.
  if (settings_.mass_scale_unobservable) {
    const ParameterTable& table = model.description().parameters();
    const std::vector<std::string> names = propagator_.mapping().names();
    std::vector<int> rows;
    for (int i = 0; i < n; ++i) {
      const int row = table.index(names[static_cast<std::size_t>(i)]);
      const std::string unit = row >= 0 ? table[row].unit : std::string();
      if (unit.rfind("kg", 0) == 0 || unit.rfind("N", 0) == 0) rows.push_back(i);
    }
    scale_ = Eigen::VectorXd::Zero(n);
    for (int i : rows) scale_[i] = prior_mean_[i] / prior_std_[i];
    const double norm = scale_.norm();
    if (rows.size() >= 2 && norm > 0.0 && std::isfinite(norm)) {
      scale_ /= norm;
    } else {
      scale_.resize(0);
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
  if (settings_.nuisance() && !angle_) {
    throw std::invalid_argument(
        "filter.horizon.cross_fall, cross_fall_walk, accel_bias and gyro_bias need the roll "
        "plane's IMU channels (accel_y, accel_z, gyro_x) read without a road");
  }
  if (settings_.clock_offset > 0.0 && !angle_) {
    throw std::invalid_argument(
        "filter.horizon.clock_offset needs the roll plane's IMU channels (accel_y, accel_z, "
        "gyro_x) read without a road");
  }
  reset();
}

double MovingHorizon::clockOffset() const {
  return offset_ < 0 ? std::numeric_limits<double>::quiet_NaN()
                     : settings_.clock_offset * mean_[offset_];
}

double MovingHorizon::shiftedOffset(double state) const {
  const double bound = 3.0 * settings_.clock_offset;
  return std::clamp(settings_.clock_offset * state, -bound, bound);
}

double MovingHorizon::differenceStep(double dt) const {
  return std::clamp(dt, 0.0, settings_.clock_offset);
}

double MovingHorizon::readingLag(double dt) const {
  return offset_ >= 0 ? 3.0 * settings_.clock_offset + differenceStep(dt) : 0.0;
}

double MovingHorizon::clockOffsetStd() const {
  return offset_ < 0 ? std::numeric_limits<double>::quiet_NaN()
                     : settings_.clock_offset * std::sqrt(std::max(0.0, cov_(offset_, offset_)));
}

void MovingHorizon::reset() {
  offset_ = settings_.clock_offset > 0.0 ? parameters_ + 1 : -1;  // after the angle
  int n = parameters_ + (angle_ ? 1 : 0) + (offset_ >= 0 ? 1 : 0);
  // The nuisance values after them.
  cross_ = bias_y_ = bias_z_ = bias_g_ = -1;
  if (angle_ && (settings_.cross_fall > 0.0 || settings_.cross_fall_walk > 0.0)) cross_ = n++;
  if (angle_ && settings_.accel_bias > 0.0) {
    bias_y_ = n++;
    bias_z_ = n++;
  }
  if (angle_ && settings_.gyro_bias > 0.0) bias_g_ = n++;
  input_count_ = settings_.input_noise_states ? propagator_.model().inputCount() : 0;
  inputs_first_ = input_count_ > 0 ? n : -1;
  n += 2 * input_count_;  // standardised: prior N(0, 1)
  mean_ = Eigen::VectorXd::Zero(n);
  cov_ = Eigen::MatrixXd::Identity(n, n);
  if (angle_) cov_(last(), last()) = 0.0;  // at rest at t = 0: no angle integrated yet
  if (cross_ >= 0) cov_(cross_, cross_) = settings_.cross_fall * settings_.cross_fall;
  const double accel = settings_.accel_bias * settings_.accel_bias;
  if (bias_y_ >= 0) cov_(bias_y_, bias_y_) = cov_(bias_z_, bias_z_) = accel;
  if (bias_g_ >= 0) cov_(bias_g_, bias_g_) = settings_.gyro_bias * settings_.gyro_bias;
  previous_time_ = 0.0;
  recent_.clear();
  anchor_rows_.clear();
  startWindow();
}

void MovingHorizon::walk(Eigen::MatrixXd& cov, double dt) const {
  if (!angle_ || !noise_ || !(dt > 0.0)) return;
  // The trapezoid's increment of the gyro's noise: variance (sigma dt)^2 / 2
  // per reading, each reading in two increments: (sigma dt)^2 a sample.
  const double sigma = noise_->channel_std.size() > gyro_ ? noise_->channel_std[gyro_] : 0.0;
  cov(last(), last()) += sigma * sigma * dt * dt;
  if (cross_ >= 0 && settings_.cross_fall_walk > 0.0) {
    // The crown's change: the gyro turns with it, so the model's roll (the
    // gyro's integral) moves off the body's roll on the axle by the same
    // increment (the angle's error and the cross-fall walk together).
    const double q = settings_.cross_fall_walk * settings_.cross_fall_walk * dt;
    cov(last(), last()) += q;
    cov(cross_, cross_) += q;
    cov(last(), cross_) += q;
    cov(cross_, last()) += q;
  }
}

void MovingHorizon::advanceInputs(const Measurement& m, Eigen::VectorXd& mean,
                                  Eigen::MatrixXd& cov) const {
  if (input_count_ == 0) return;
  for (int i = 0; i < input_count_; ++i) {
    const int now = inputs_first_ + i, before = now + input_count_;
    const double rho = carriesInputs(m) ? m.input_correlation[i] : 0.0;
    mean[before] = mean[now];
    mean[now] *= rho;
    cov.row(before) = cov.row(now);
    cov.col(before) = cov.col(now);
    cov.row(now) *= rho;
    cov.col(now) *= rho;
    cov(now, now) += 1.0 - rho * rho;
  }
}

void MovingHorizon::startWindow() {
  window_mean_ = mean_;
  window_cov_ = cov_;
  kept_.clear();
  window_start_ = -1.0;  // set by the window's first sample
}

bool MovingHorizon::readingsAt(const Eigen::MatrixXd& th, double time, Eigen::ArrayXXd& y,
                               Workspace& ws, double shift, const Eigen::VectorXd& roll,
                               const Eigen::VectorXd& lateral) const {
  const MechanicalModel& model = propagator_.model();
  y = Eigen::ArrayXXd::Zero(model.stateSize(), th.cols());
  if (!anchor_rows_.empty()) return anchoredReadings(th, time, y, shift, roll, lateral, ws);
  Prepared& kept = ws.prepared[th.cols() == 1 ? 1 : 0];
  Eigen::MatrixXd full = propagator_.mapping().fullParameters(th);
  const bool offsets = roll.size() > 0;
  if (!(kept.batch && kept.offsets == offsets && kept.full.cols() == full.cols() && kept.full == full)) {
    kept.batch.reset();
    for (Eigen::Index q = 0; q < full.cols(); ++q) {
      if (!model.invalidReason(full.col(q)).empty()) return false;
    }
    kept.batch = model.prepare(full);
    kept.full = std::move(full);
    kept.offsets = offsets;
  }
  ModelBatch& batch = *kept.batch;
  if (offsets && !batch.offsetPoints(roll, lateral)) return false;
  batch.readingsShifted(time, shift, y);
  ws.evaluations += th.cols();
  return true;
}

bool MovingHorizon::predict(const Measurement& m, double dt, const NoiseModel& noise,
                            const Eigen::VectorXd& at, Eigen::VectorXd* values,
                            Eigen::VectorXd* z0, Eigen::MatrixXd* jacobian,
                            Eigen::VectorXd* variances, Workspace& ws) const {
  const MechanicalModel& model = propagator_.model();
  const int n = parameters_;
  const int c = static_cast<int>(m.channels.size());
  // Column 0 the point, column i + 1 one step along parameter i: each
  // column's theta differs from the point's in one entry only.
  const Eigen::VectorXd point = theta(at.head(n));
  Eigen::VectorXd steps(n);
  Eigen::MatrixXd th(n, n + 1);
  th.colwise() = point;
  for (int i = 0; i < n; ++i) {
    // A step inside the support (backwards near its upper end).
    double h = settings_.step;
    const double up = point[i] + h * prior_std_[i];
    if (!(up < upper_[i])) h = -h;
    steps[i] = h;
    th(i, i + 1) = prior_mean_[i] + prior_std_[i] * (at[i] + h);
  }
  // readingsAt refuses a point that is not admissible (false).
  // With a clock offset the IMU stamped m.time read what the inputs drove
  // at m.time - offset.
  const double shift = offset_ >= 0 ? shiftedOffset(at[offset_]) : 0.0;
  // Nuisance values: the model's roll is the gyro's integral less the
  // angle's error (the crown's change and the gyro's noise) and the gyro
  // bias's drift, so the body's moments see the true tilt too; the road's
  // cross-fall beta adds g sin(beta) to a_y. Two more columns at the mean:
  // one step in the roll, one in beta (the slopes).
  const bool nuisance = settings_.nuisance();
  constexpr double kRollStep = 1e-4;  // rad
  Eigen::VectorXd rolls, laterals;
  Eigen::MatrixXd thx = th;
  double roll = 0.0, lateral = 0.0;
  if (nuisance) {
    roll = -(at[n] + (bias_g_ >= 0 ? at[bias_g_] * m.time : 0.0));
    lateral = cross_ >= 0 ? kCrossFallGravity * std::sin(at[cross_]) : 0.0;
    const int extra = cross_ >= 0 ? 2 : 1;
    thx.resize(th.rows(), n + 1 + extra);
    thx.leftCols(n + 1) = th;
    for (int e = 0; e < extra; ++e) thx.col(n + 1 + e) = th.col(0);
    rolls = Eigen::VectorXd::Constant(n + 1 + extra, roll);
    laterals = Eigen::VectorXd::Constant(n + 1 + extra, lateral);
    rolls[n + 1] = roll - kRollStep;
    if (cross_ >= 0) laterals[n + 2] = kCrossFallGravity * std::sin(at[cross_] + kRollStep);
  }
  Eigen::ArrayXXd y;
  if (!readingsAt(thx, m.time, y, ws, shift, rolls, laterals)) return false;
  Eigen::MatrixXd z(c, y.cols());
  for (int r = 0; r < c; ++r) {
    z.row(r) = model.observationMatrix().row(m.channels[static_cast<std::size_t>(r)]) * y.matrix();
  }
  if (!z.allFinite()) return false;
  jacobian->setZero(c, static_cast<Eigen::Index>(at.size()));
  for (int i = 0; i < n; ++i) jacobian->col(i) = (z.col(i + 1) - z.col(0)) / steps[i];
  if (scale_.size() == n) {
    // No slope along the prior's mass scale. At `at` the readings' slope is 0
    // along at's own scale direction, which turns as the estimate moves; the
    // updates linearised at different points would together inform the scale
    // that no reading holds (and walk the estimate along it). Held to one
    // direction, the scale keeps the prior's information.
    const Eigen::VectorXd along = jacobian->leftCols(n) * scale_;
    jacobian->leftCols(n).noalias() -= along * scale_.transpose();
  }
  *z0 = z.col(0);
  if (nuisance) {
    // The slope in the angle's error: a forward difference of the model's
    // roll (the error is minus the roll offset); the gyro bias's is it times
    // the time since the start. The biases add to their channels.
    for (int r = 0; r < c; ++r) {
      const int ch = m.channels[static_cast<std::size_t>(r)];
      (*jacobian)(r, n) = (z(r, n + 1) - z(r, 0)) / kRollStep;
      if (cross_ >= 0) (*jacobian)(r, cross_) = (z(r, n + 2) - z(r, 0)) / kRollStep;
      if (bias_g_ >= 0) (*jacobian)(r, bias_g_) = (*jacobian)(r, n) * m.time;
      if (bias_y_ >= 0 && ch == accel_y_) {
        (*jacobian)(r, bias_y_) = 1.0;
        (*z0)[r] += at[bias_y_];
      }
      if (bias_z_ >= 0 && ch == accel_z_) {
        (*jacobian)(r, bias_z_) = 1.0;
        (*z0)[r] += at[bias_z_];
      }
    }
  } else if (angle_) {
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
  if (offset_ >= 0) {
    // The slope in the offset: a central difference a sample (at most the
    // offset's prior std: a decimated stream reads the full-rate inputs)
    // either side of the shifted instant (the caller hands samples over once
    // the inputs after it are in: readingLag). The difference of inputs one sample
    // apart carries a few hundredths of the rate's spread: no errors in
    // variables to speak of.
    jacobian->col(offset_).setZero();
    const double h = differenceStep(dt);
    if (h > 0.0) {
      Eigen::ArrayXXd later, earlier;
      const Eigen::VectorXd r1 = Eigen::VectorXd::Constant(nuisance ? 1 : 0, roll);
      const Eigen::VectorXd l1 = Eigen::VectorXd::Constant(nuisance ? 1 : 0, lateral);
      if (!readingsAt(th.col(0), m.time, later, ws, shift + h, r1, l1)) return false;
      if (!readingsAt(th.col(0), m.time, earlier, ws, shift - h, r1, l1)) return false;
      const Eigen::VectorXd slope =
          (later.matrix().col(0) - earlier.matrix().col(0)) * (settings_.clock_offset / (2.0 * h));
      for (int r = 0; r < c; ++r) {
        (*jacobian)(r, offset_) = model.observationMatrix().row(m.channels[static_cast<std::size_t>(r)]) * slope;
      }
    }
    // Beyond the bound the prediction was taken at it.
    *z0 += jacobian->col(offset_) * (at[offset_] - shift / settings_.clock_offset);
  }
  Measurement left;  // m's R without what the input states carry
  const bool inputs = carriesInputs(m);
  if (inputs) {
    for (int i = 0; i < 2 * input_count_; ++i) jacobian->col(inputs_first_ + i) = -m.input_slopes.col(i);
    *z0 += jacobian->middleCols(inputs_first_, 2 * input_count_) *
           at.segment(inputs_first_, 2 * input_count_);
    left.time = m.time;
    left.channels = m.channels;
    left.values = m.values;
    left.variances = m.variances;
    left.extra_covariance = m.extra_covariance - inputSlopesCovariance(m.input_slopes, m.input_correlation);
  }
  const NoiseWhitening white(noise, inputs ? left : m);
  *values = m.values;
  white.whiten(*values);
  white.whiten(*z0);
  white.whiten(*jacobian);
  *variances = white.variances();
  return true;
}

namespace {

// Kalman update of (mean, cov) by one whitened sample linearised at `at`:
// prediction z0 + J (mean - at).
void linearUpdate(const Eigen::VectorXd& values, const Eigen::VectorXd& z0,
                  const Eigen::MatrixXd& j, const Eigen::VectorXd& r, const Eigen::VectorXd& at,
                  Eigen::VectorXd& mean, Eigen::MatrixXd& cov, UpdateDiagnostics* d) {
  const Eigen::VectorXd innovation = values - z0 - j * (mean - at);
  // The products by smallProduct (a state of some forty against a few
  // channels: Eigen's blocked GEMM spent more on packing than on arithmetic).
  const Eigen::Index n = cov.rows(), c = j.rows();
  Eigen::MatrixXd pj(n, c);  // P J^T
  smallProduct(cov.data(), j.data(), c, 1, pj.data(), n, n, c);
  Eigen::MatrixXd s(c, c);  // J P J^T + R
  smallProduct(j.data(), pj.data(), 1, n, s.data(), c, n, c);
  s.diagonal() += r;
  const Eigen::LLT<Eigen::MatrixXd> llt(s);
  if (llt.info() != Eigen::Success) {
    d->finite = false;
    d->singular = true;
    return;
  }
  // With the gain optimal, the Joseph form equals P - K S K^T = P - W W^T,
  // W = P J^T L^-T (S = L L^T): c columns instead of three N x N products,
  // symmetric by construction.
  Eigen::MatrixXd w = pj;
  llt.matrixU().solveInPlace<Eigen::OnTheRight>(w);  // W L^T = P J^T
  d->innovation = innovation;
  const Eigen::VectorXd white = llt.matrixL().solve(innovation);
  d->nis = white.squaredNorm();
  d->channels = static_cast<int>(values.size());
  mean.noalias() += w * white;
  Eigen::MatrixXd ww(n, n);  // W W^T
  smallProduct(w.data(), w.data(), n, 1, ww.data(), n, c, n);
  cov -= ww;  // (the lower triangle counts: copied to the upper)
  cov.triangularView<Eigen::StrictlyUpper>() = cov.transpose();
  d->finite = mean.allFinite() && cov.allFinite() && std::isfinite(d->nis);
}

}  // namespace

HorizonStep MovingHorizon::propose(const Measurement& m, const NoiseModel& noise,
                                   Eigen::VectorXd* mean, Eigen::MatrixXd* cov) {
  noise_ = &noise;
  HorizonStep s;
  walk(cov_, m.time - previous_time_);
  advanceInputs(m, mean_, cov_);
  *mean = mean_;
  *cov = cov_;
  if (m.channels.empty()) return s;
  // Iterated: when the update lands further than `shift` posterior std
  // from where it was linearised (a wide prior, a load just re-opened), the
  // sample is linearised again at that posterior mean, from the same prior.
  at_ = mean_;
  for (int pass = 0;; ++pass) {
    Eigen::VectorXd values, z0, r;
    Eigen::MatrixXd j;
    *mean = mean_;
    *cov = cov_;
    // The offset's slope needs a sample before this one.
    const double dt = previous_time_ > 0.0 ? m.time - previous_time_ : 0.0;
    const bool ok = predict(m, dt, noise, at_, &values, &z0, &j, &r, own_);
    if (!ok) {
      s.update = UpdateDiagnostics();
      s.update.finite = false;
      return s;
    }
    s.update = UpdateDiagnostics();
    linearUpdate(values, z0, j, r, at_, *mean, *cov, &s.update);
    if (!s.update.finite || pass >= settings_.reruns) return s;
    const Eigen::ArrayXd sd = cov->diagonal().head(parameters_).cwiseMax(0.0).cwiseSqrt().array();
    const Eigen::ArrayXd away = (*mean - at_).head(parameters_).array().abs();
    if (!((away / sd).maxCoeff() > settings_.shift)) return s;
    at_ = *mean;
  }
}

void MovingHorizon::accept(const Measurement& m, HorizonStep& s, const Eigen::VectorXd& mean,
                           const Eigen::MatrixXd& cov, bool damp) {
  if (window_start_ < 0.0) window_start_ = m.time;
  const double dt = m.time - previous_time_;
  previous_time_ = m.time;
  last_gap_ = dt;
  const bool used = s.update.finite && !s.gated && !m.channels.empty();
  if (used) {
    if (damp) {
      s.damping = supportDamping(theta(mean_.head(parameters_)), theta(mean.head(parameters_)),
                                 lower_, upper_);
    }
    mean_ += s.damping * (mean - mean_);
    cov_ += s.damping * (cov - cov_);
  }
  kept_.push_back({m, dt, at_, used});
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
    // Every prediction is at `at`, independent of the updates: the later
    // samples' are made on a second thread while this one predicts the
    // earlier ones and updates (the same numbers: each is a function of its
    // sample and `at`).
    struct Predicted {
      bool ok = false;
      Eigen::VectorXd values, z0, r;
      Eigen::MatrixXd j;
    };
    std::vector<Predicted> predicted(kept_.size());
    const auto predictOne = [&](std::size_t i, Workspace& ws) {
      const Kept& k = kept_[i];
      Predicted& p = predicted[i];
      p.ok = predict(k.m, k.m.time - k.dt > 0.0 ? k.dt : 0.0, *noise_, at, &p.values, &p.z0, &p.j,
                     &p.r, ws);
    };
    // The filter's thread also updates: it takes the first ~40 %.
    const std::size_t split = kept_.size() * 2 / 5;
    const bool helper = kept_.size() >= 16;
    std::future<void> later;
    bool helped = false;  // its predictions are in
    if (helper) {
      later = std::async(std::launch::async, [&] {
        // Up to the first failure, as the sequential loop would go.
        for (std::size_t i = split; i < kept_.size(); ++i) {
          if (!kept_[i].used) continue;
          predictOne(i, helper_);
          if (!predicted[i].ok) break;
        }
      });
    }
    bool ok = true;
    for (std::size_t i = 0; i < kept_.size(); ++i) {
      Kept& k = kept_[i];
      walk(cov, k.dt);
      advanceInputs(k.m, mean, cov);
      if (!k.used) continue;
      if (!helper || i < split) {
        predictOne(i, own_);
      } else if (!helped) {
        later.get();  // the helper's predictions (rethrows its exception)
        helped = true;
      }
      const Predicted& p = predicted[i];
      UpdateDiagnostics d;
      if (!p.ok) {
        ok = false;
        break;
      }
      linearUpdate(p.values, p.z0, p.j, p.r, at, mean, cov, &d);
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
  // A square root L L^T = cov (LDLT with pivoting tolerates a singular cov):
  // column j of P^T L sqrt(D), scaled by the prior std, into the term of
  // germ j (the products in Eigen's order, without the temporaries).
  Eigen::MatrixXd pl = Eigen::MatrixXd(ldlt.matrixL());
  pl = ldlt.transpositionsP().transpose() * pl;
  const Eigen::VectorXd root = ldlt.vectorD().cwiseMax(0.0).cwiseSqrt();
  for (int j = 0; j < n; ++j) {
    double* out = c.col(degree_one_[static_cast<std::size_t>(j)]).data();
    for (int i = 0; i < n; ++i) out[i] = prior_std_[i] * (pl(i, j) * root[j]);
  }
  return c;
}

void MovingHorizon::restore(const Eigen::MatrixXd& coefficients) {
  const int n = parameters_;
  if (coefficients.rows() != n) throw std::invalid_argument("moving horizon: wrong parameter count");
  const Eigen::MatrixXd higher =
      prior_std_.cwiseInverse().asDiagonal() * coefficients.rightCols(coefficients.cols() - 1);
  // The angle's error and the clock offset are not in a checkpoint: they
  // go on where they were.
  const int extra = static_cast<int>(mean_.size()) - n;
  const Eigen::VectorXd extra_mean = mean_.tail(extra);
  const Eigen::MatrixXd extra_cov = cov_.bottomRightCorner(extra, extra);
  mean_.head(n) = (pcMean(coefficients) - prior_mean_).cwiseQuotient(prior_std_);
  cov_.setZero();
  cov_.topLeftCorner(n, n) = higher * higher.transpose();
  mean_.tail(extra) = extra_mean;
  cov_.bottomRightCorner(extra, extra) = extra_cov;
  recent_.clear();
  startWindow();
}

void MovingHorizon::reopen(const std::vector<int>& rows) {
  if (!(angle_ && previous_time_ > 0.0 && reanchorAngle(rows))) {
    for (int r : rows) {
      mean_[r] = 0.0;
      cov_.row(r).setZero();
      cov_.col(r).setZero();
      cov_(r, r) = 1.0;
    }
  }
  startWindow();
}

bool MovingHorizon::reanchorAngle(const std::vector<int>& rows) {
  // The model's roll angle is its static tilt under the parameters plus the
  // gyro's integral since the start, so the angle's error e = tilt(vehicle,
  // load) - tilt at the start's true load. From the first load change on,
  // the tilt is taken at the start's load (its mean now: anchoredReadings),
  // whatever the current load: e_new = e_old + tilt(anchor) - tilt(old
  // load), linear in the old load around its mean (its spread moves into
  // e), and the new load starts from its prior apart from the angle.
  const int n = parameters_;
  const int k = static_cast<int>(rows.size());
  if (k == 0 || k >= n) return false;
  const bool first = anchor_rows_.empty();
  const int size = static_cast<int>(mean_.size());  // parameters, angle, clock offset
  Eigen::MatrixXd t = Eigen::MatrixXd::Zero(size, size + k);
  for (int i = 0; i < size; ++i) t(i, i) = 1.0;
  if (first) {
    const MechanicalModel& model = propagator_.model();
    Eigen::MatrixXd zeta(n, k + 1);
    for (int c = 0; c <= k; ++c) zeta.col(c) = mean_.head(n);
    Eigen::VectorXd steps(k);
    for (int j = 0; j < k; ++j) {
      const int r = rows[static_cast<std::size_t>(j)];
      steps[j] = theta(mean_.head(n))[r] + settings_.step * prior_std_[r] < upper_[r] ? settings_.step
                                                                                      : -settings_.step;
      zeta(r, 1 + j) += steps[j];
    }
    Eigen::MatrixXd th(n, k + 1);
    for (int c = 0; c <= k; ++c) th.col(c) = theta(zeta.col(c));
    const Eigen::MatrixXd full = propagator_.mapping().fullParameters(th);
    for (int c = 0; c <= k; ++c) {
      if (!model.invalidReason(full.col(c)).empty()) return false;
    }
    Eigen::ArrayXXd y = Eigen::ArrayXXd::Zero(model.stateSize(), k + 1);
    model.prepare(full)->readings(previous_time_, y);
    evaluations_ += k + 1;
    const Eigen::ArrayXd tilt = tilts(y);
    if (!tilt.allFinite()) return false;
    for (int j = 0; j < k; ++j) {
      t(last(), rows[static_cast<std::size_t>(j)]) = -(tilt[1 + j] - tilt[0]) / steps[j];
    }
    anchor_rows_ = rows;
    anchor_ = theta(mean_.head(n));
  }
  for (int j = 0; j < k; ++j) {
    const int r = rows[static_cast<std::size_t>(j)];
    t(r, r) = 0.0;
    t(r, size + j) = 1.0;
    mean_[r] = 0.0;
  }
  Eigen::MatrixXd joint = Eigen::MatrixXd::Zero(size + k, size + k);
  joint.topLeftCorner(size, size) = cov_;
  joint.bottomRightCorner(k, k).setIdentity();
  const Eigen::MatrixXd cov = t * joint * t.transpose();
  cov_ = 0.5 * (cov + cov.transpose());
  return true;
}

Eigen::ArrayXd MovingHorizon::tilts(const Eigen::ArrayXXd& y) const {
  const Eigen::MatrixXd& h = propagator_.model().observationMatrix();
  const Eigen::ArrayXd ay = (h.row(accel_y_) * y.matrix()).transpose().array();
  const Eigen::ArrayXd az = (h.row(accel_z_) * y.matrix()).transpose().array();
  return ay.binaryExpr(az, [](double a, double b) { return std::atan2(a, b); });
}

bool MovingHorizon::anchoredReadings(const Eigen::MatrixXd& th, double time, Eigen::ArrayXXd& y,
                                     double shift, const Eigen::VectorXd& roll,
                                     const Eigen::VectorXd& lateral, Workspace& ws) const {
  // Each column twice: as it is and with the load at the anchor. The second
  // gives the tilt the body has at the anchor (the gyro's integral is the
  // same in both); accel_y and accel_z are turned to it (tare: no offsets).
  const MechanicalModel& model = propagator_.model();
  const Eigen::Index cols = th.cols();
  Eigen::MatrixXd both(th.rows(), 2 * cols);
  both.leftCols(cols) = th;
  both.rightCols(cols) = th;
  for (int r : anchor_rows_) both.row(r).tail(cols).setConstant(anchor_[r]);
  const Eigen::MatrixXd full = propagator_.mapping().fullParameters(both);
  for (Eigen::Index c = 0; c < 2 * cols; ++c) {
    if (!model.invalidReason(full.col(c)).empty()) return false;
  }
  Eigen::ArrayXXd all = Eigen::ArrayXXd::Zero(model.stateSize(), 2 * cols);
  auto batch = model.prepare(full);
  if (roll.size() > 0) {  // both halves
    Eigen::VectorXd r2(2 * cols), l2(2 * cols);
    r2 << roll, roll;
    l2 << lateral, lateral;
    if (!batch->offsetPoints(r2, l2)) return false;
  }
  batch->readingsShifted(time, shift, all);
  ws.evaluations += 2 * cols;
  const Eigen::ArrayXd tilt = tilts(all);
  y = all.leftCols(cols);
  const Eigen::MatrixXd& h = model.observationMatrix();
  // The rows of y that accel_y and accel_z read (reading states: one each).
  Eigen::Index row_y = -1, row_z = -1;
  h.row(accel_y_).cwiseAbs().maxCoeff(&row_y);
  h.row(accel_z_).cwiseAbs().maxCoeff(&row_z);
  for (Eigen::Index c = 0; c < cols; ++c) {
    const double d = tilt[cols + c] - tilt[c];
    const double ay = y(row_y, c), az = y(row_z, c);
    y(row_y, c) = ay * std::cos(d) + az * std::sin(d);
    y(row_z, c) = az * std::cos(d) - ay * std::sin(d);
  }
  return y.allFinite();
}

double MovingHorizon::windowStart() const {
  double t = std::numeric_limits<double>::infinity();
  double gap = 0.0;
  if (!kept_.empty()) {
    t = kept_.front().m.time;
    gap = kept_.front().dt;
  }
  if (!recent_.empty() && recent_.front().m.time < t) {
    t = recent_.front().m.time;
    gap = t - recent_.front().previous_time;
  }
  // The clock offset reads the inputs up to 3 prior std and a difference
  // step (at most one more) before a sample (and the sample before that),
  // for the samples the caller still holds (after the last one taken) too.
  if (offset_ >= 0 && previous_time_ > 0.0 && !(previous_time_ > t)) {
    t = previous_time_;
    gap = last_gap_;
  }
  if (offset_ >= 0 && std::isfinite(t)) t -= 4.0 * settings_.clock_offset + std::max(gap, 0.0);
  return t;
}

void MovingHorizon::keepRecent(int count) {
  recent_capacity_ = static_cast<std::size_t>(std::max(0, count));
  while (recent_.size() > recent_capacity_) recent_.pop_front();
}

void MovingHorizon::remember(Recent r) {
  if (recent_capacity_ == 0) return;
  if (recent_.size() == recent_capacity_) recent_.pop_front();
  recent_.push_back(std::move(r));
}

int MovingHorizon::samplesSinceChange(int within, const std::function<double(int)>& level) const {
  const std::size_t span = std::min(recent_.size(), static_cast<std::size_t>(std::max(0, within)));
  if (span == 0) return 0;
  const std::size_t first = recent_.size() - span;
  std::size_t start = recent_.size() - 1;
  double sum = 0.0, best = -std::numeric_limits<double>::infinity();
  for (std::size_t k = recent_.size(); k-- > first;) {
    if (recent_[k].dof > 0) sum += recent_[k].nis - level(recent_[k].dof);
    if (sum > best) {
      best = sum;
      start = k;
    }
  }
  return static_cast<int>(recent_.size() - start);
}

std::vector<Measurement> MovingHorizon::rewind(int back) {
  std::vector<Measurement> again;
  if (back <= 0 || static_cast<std::size_t>(back) > recent_.size()) return again;
  const std::size_t start = recent_.size() - static_cast<std::size_t>(back);
  mean_ = recent_[start].mean;
  cov_ = recent_[start].cov;
  previous_time_ = recent_[start].previous_time;
  for (std::size_t k = start; k < recent_.size(); ++k) again.push_back(std::move(recent_[k].m));
  recent_.erase(recent_.begin() + static_cast<std::ptrdiff_t>(start), recent_.end());
  startWindow();
  return again;
}

void MovingHorizon::drift(const Eigen::VectorXd& intensity, double dt) {
  if (intensity.size() != parameters_ || !(dt > 0.0)) return;
  cov_.diagonal().head(parameters_).array() +=
      (intensity.cwiseQuotient(prior_std_)).array().square() * dt;
}

}  // namespace pc_ekf
