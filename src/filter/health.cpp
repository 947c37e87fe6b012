#include "pc_ekf/filter/health.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <mutex>
#include <sstream>
#include <tuple>

#include "pc_ekf/pc/basis_key.h"
#include "pc_ekf/pc/orthonormal_family.h"
#include "pc_ekf/pc/pc_statistics.h"

namespace pc_ekf {

double chiSquareQuantile(double probability, double dof) {
  // chi2(k) = 2 Gamma(k/2, 1).
  const OrthonormalFamily gamma(GermSpec{GermFamily::kGamma, dof / 2.0, 1.0});
  return 2.0 * gamma.inverseCdf(probability);
}

RateSettings rateSettings(const HealthSettings& health, double innovation_gate) {
  RateSettings r;
  r.confidence = health.nis_confidence;
  r.window = health.rate_window;
  r.gate_probability = innovation_gate;
  r.damp_fraction = 1.0 - health.nis_confidence;
  // Allowance of the support rate (reported, a warning only: SafeguardRates::flagged).
  r.support_fraction = 0.1;
  r.reopen_rate = 1.0 / health.reopen_interval;
  return r;
}

std::vector<std::string> HealthStatus::warnings() const {
  std::vector<std::string> w;
  std::ostringstream o;
  if (non_finite) w.push_back("non-finite filter state");
  if (forecast_failed) w.push_back("forecast failed: too few usable collocation points");
  if (nis_window_outside) {
    o << "windowed NIS mean " << nis_window_mean << " outside [" << window_lower << ", "
      << window_upper << "]";
    w.push_back(o.str());
  }
  if (support_exceeded) w.push_back("parameter PDF mass outside the prior support");
  if (gated) w.push_back("innovation gate: sample not used (NIS " + std::to_string(nis) + ")");
  if (damped) {
    w.push_back("update damped: the data pushed a parameter mean out of its prior support "
                "(model error, or a parameter that should be declared uncertain)");
  }
  if (reopened) w.push_back("uncertainty re-opened after a persistent NIS violation");
  for (const std::string& r : rates.warnings()) w.push_back(r);
  if (loo_exceeded) {
    o.str("");
    o << "projection leave-one-out error " << loo_error.maxCoeff()
      << " above the warning threshold (raise pc.order or the collocation design)";
    w.push_back(o.str());
  }
  return w;
}

namespace {

// The support draws' basis values (HealthMonitor::SupportDraws) depend only on
// the basis, the draws and the seed: the filters of one run (full rate,
// coherence, a deferred re-run's) share them instead of drawing them again.
using SupportKey = std::tuple<BasisKey, int, std::uint64_t>;

std::shared_ptr<const HealthMonitor::SupportDraws> supportDraws(const PolynomialBasis& basis,
                                                                int draws, std::uint64_t seed) {
  SupportKey key{basisKey(basis), draws, seed};
  static std::mutex mutex;
  static std::vector<std::pair<SupportKey, std::shared_ptr<const HealthMonitor::SupportDraws>>> cache;
  std::lock_guard<std::mutex> lock(mutex);
  for (const auto& [k, v] : cache) {
    if (k == key) return v;
  }
  auto d = std::make_shared<HealthMonitor::SupportDraws>();
  // The basis at the draws and at kPad points more (each row is its point's
  // alone), those rows then zeroed: the padded matrix without a copy of it.
  const Eigen::MatrixXd germs = sampleGerms(basis, draws, seed);
  const Eigen::Index rows = germs.rows(), terms = static_cast<Eigen::Index>(basis.size());
  Eigen::MatrixXd points = Eigen::MatrixXd::Zero(rows + HealthMonitor::SupportDraws::kPad, germs.cols());
  points.topRows(rows) = germs;
  d->draws = rows;
  d->padded = basis.evaluate(points);
  d->padded.bottomRows(HealthMonitor::SupportDraws::kPad).setZero();
  const auto psi = d->padded.topRows(rows);
  d->max_abs = rows > 0 ? Eigen::VectorXd(psi.cwiseAbs().colwise().maxCoeff().transpose())
                        : Eigen::VectorXd::Zero(terms);
  const auto& indices = basis.multiIndices();
  for (std::size_t j = 0; j < indices.size(); ++j) {
    int degree = 0;
    for (int k : indices[j]) degree += k;
    if (degree == 1) d->first_degree.push_back(static_cast<Eigen::Index>(j));
  }
  d->first = psi(Eigen::all, d->first_degree);
  if (cache.size() >= 4) cache.erase(cache.begin());
  cache.emplace_back(std::move(key), d);
  return d;
}

}  // namespace

namespace {

// out[d] = mean + sum_j c_j first(d, j) (first: draws x f, column-major), eight
// draws at a time in registers (compiled for x86-64-v3 and the baseline). The
// summation order does not matter to the count: massOutside's margin covers it.
__attribute__((target_clones("arch=x86-64-v3", "default"))) void firstDegreeValues(
    const double* __restrict first, Eigen::Index draws, const double* __restrict c, Eigen::Index f,
    double mean, double* __restrict out) {
  // Two four-lane vectors (GCC vector extensions: AVX2 FMA in the x86-64-v3 clone).
  using Lanes = double __attribute__((vector_size(32)));
  constexpr int kLanes = 8;
  Eigen::Index d0 = 0;
  for (; d0 + kLanes <= draws; d0 += kLanes) {
    Lanes a = {mean, mean, mean, mean}, b = a;
    for (Eigen::Index j = 0; j < f; ++j) {
      const double* col = first + j * draws + d0;
      Lanes x, y;
      std::memcpy(&x, col, sizeof(x));
      std::memcpy(&y, col + 4, sizeof(y));
      a += c[j] * x;
      b += c[j] * y;
    }
    std::memcpy(out + d0, &a, sizeof(a));
    std::memcpy(out + d0 + 4, &b, sizeof(b));
  }
  for (; d0 < draws; ++d0) {
    double v = mean;
    for (Eigen::Index j = 0; j < f; ++j) v += c[j] * first[j * draws + d0];
    out[d0] = v;
  }
}

}  // namespace

HealthMonitor::HealthMonitor(const PcPropagator& propagator, const HealthSettings& settings)
    : settings_(settings),
      draws_(supportDraws(propagator.basis(), settings.support_draws, settings.seed)) {
  const int n = propagator.parameterCount();
  near_.resize(draws_->draws);
  lower_.resize(n);
  upper_.resize(n);
  for (int i = 0; i < n; ++i) {
    lower_[i] = propagator.mapping().lowerBound(i);
    upper_[i] = propagator.mapping().upperBound(i);
  }
}

void HealthMonitor::reset() {
  window_.clear();
  last_mean_.resize(0);
  last_std_.resize(0);
}

double HealthMonitor::nisBound(bool upper, int dof) {
  std::vector<double>& cache = bound_cache_[upper ? 1 : 0];
  if (dof >= static_cast<int>(cache.size())) {
    cache.resize(dof + 1, std::numeric_limits<double>::quiet_NaN());
  }
  double& bound = cache[dof];
  if (std::isnan(bound)) {
    const double tail = (1.0 - settings_.nis_confidence) / 2.0;
    bound = chiSquareQuantile(upper ? 1.0 - tail : tail, dof);
  }
  return bound;
}

double HealthMonitor::spreadBound(const Eigen::MatrixXd& coeffs, Eigen::Index i,
                                  double* slack) const {
  // Every draw's value lies in mean +- spread (|psi_j| <= max_abs_j), up to the
  // dot product's round-off (bounded by S eps (|mean| + spread); 4x margin).
  const Eigen::VectorXd& max_abs = draws_->max_abs;
  double spread = 0.0;
  for (Eigen::Index j = 1; j < coeffs.cols(); ++j) spread += std::abs(coeffs(i, j)) * max_abs[j];
  *slack = 4.0 * static_cast<double>(coeffs.cols()) * std::numeric_limits<double>::epsilon() *
           (std::abs(coeffs(i, 0)) + spread);
  return spread;
}

bool HealthMonitor::boundedInside(const Eigen::MatrixXd& coeffs, Eigen::Index i) const {
  double slack = 0.0;
  const double spread = spreadBound(coeffs, i, &slack), mean = coeffs(i, 0);
  return mean - spread - slack >= lower_[i] && mean + spread + slack <= upper_[i];
}

double HealthMonitor::massOutside(const Eigen::MatrixXd& coeffs, Eigen::Index i, const double* near) {
  const Eigen::Index draws = draws_->draws;
  const Eigen::VectorXd& max_abs = draws_->max_abs;
  if (draws == 0) return std::numeric_limits<double>::quiet_NaN();  // mean of no draws
  const double lower = lower_[i], upper = upper_[i], mean = coeffs(i, 0);
  const Eigen::Index terms = coeffs.cols();
  // When the bounds are inside the support, no draw is outside: the common
  // case once the data have narrowed the PDF.
  double slack = 0.0;
  const double spread = spreadBound(coeffs, i, &slack);
  if (mean - spread - slack >= lower && mean + spread + slack <= upper) return 0.0;
  // Otherwise per draw: the mean plus the first-degree terms (the bulk of a
  // parameter's spread, n products per draw instead of S) is within `rest`
  // (the higher terms' bounds) + slack of the value, so only the draws where
  // that reaches a bound need the value itself, summed as psi * c sums it
  // (gemvValue): the count is the full product's. Summed in any order, the
  // first-degree part is within f eps spread <= slack of itself.
  double rest = spread;
  for (Eigen::Index j : draws_->first_degree) rest -= std::abs(coeffs(i, j)) * max_abs[j];
  if (!near) {
    near_.setConstant(mean);
    for (Eigen::Index j : draws_->first_degree) near_ += coeffs(i, j) * draws_->padded.col(j).head(draws);
    near = near_.data();
  }
  // `rest` by subtraction carries round-off of the order of spread eps: twice the slack covers it.
  const double margin = std::max(rest, 0.0) + 2.0 * slack;
  candidates_.clear();
  for (Eigen::Index d = 0; d < draws; ++d) {
    if (!(near[d] - margin >= lower && near[d] + margin <= upper)) candidates_.push_back(d);
  }
  // Many candidates (a parameter spread over many germs): left to fullProducts.
  if (static_cast<Eigen::Index>(candidates_.size()) * 8 > draws) return -1.0;
  row_ = coeffs.row(i);
  const Eigen::MatrixXd& padded = draws_->padded;  // one draw's values a column apart
  const int block_cols = gemvBlockColumns(draws, terms);
  Eigen::Index outside = 0;
  for (Eigen::Index d : candidates_) {
    const double v = gemvValue(padded.data() + d, padded.rows(), row_.data(), terms, block_cols);
    outside += (v < lower) || (v > upper);
  }
  return static_cast<double>(outside) / static_cast<double>(draws);
}

void HealthMonitor::fullProducts(const Eigen::MatrixXd& coeffs, Eigen::VectorXd& mass) {
  std::vector<Eigen::Index> rows;
  for (Eigen::Index i = 0; i < mass.size(); ++i) {
    if (mass[i] < 0.0) rows.push_back(i);
  }
  if (rows.empty()) return;
  // All of them in one pass over the draws, a block of draws at a time (its
  // basis values stay in cache for every parameter), each value summed as
  // psi * c sums it (gemvOrderValues).
  const Eigen::MatrixXd& padded = draws_->padded;
  const int draws = static_cast<int>(draws_->draws), terms = static_cast<int>(coeffs.cols());
  const int block_cols = gemvBlockColumns(draws, terms);
  constexpr int kBlock = 256;
  Eigen::MatrixXd c = coeffs(rows, Eigen::all).transpose();  // terms x rows, contiguous per row
  std::vector<Eigen::Index> outside(rows.size(), 0);
  std::vector<const double*> psi(static_cast<std::size_t>(terms));
  double values[kBlock];
  for (int d0 = 0; d0 < draws; d0 += kBlock) {
    const int count = std::min(kBlock, draws - d0);
    for (int j = 0; j < terms; ++j) psi[j] = padded.col(j).data() + d0;
    for (std::size_t r = 0; r < rows.size(); ++r) {
      gemvOrderValues(psi.data(), c.col(static_cast<Eigen::Index>(r)).data(), terms, block_cols,
                      count, values);
      const double lower = lower_[rows[r]], upper = upper_[rows[r]];
      for (int b = 0; b < count; ++b) outside[r] += (values[b] < lower) || (values[b] > upper);
    }
  }
  for (std::size_t r = 0; r < rows.size(); ++r) {
    mass[rows[r]] = static_cast<double>(outside[r]) / static_cast<double>(draws);
  }
}

void HealthMonitor::assessSupport(const Eigen::MatrixXd& coeffs, HealthStatus* h) {
  h->mass_outside_support = Eigen::VectorXd::Zero(coeffs.rows());
  h->support_exceeded = false;
  if (h->non_finite) return;
  // The first-degree part of every parameter not bounded inside, as one product.
  std::vector<Eigen::Index> open;
  for (Eigen::Index i = 0; i < coeffs.rows(); ++i) {
    if (!boundedInside(coeffs, i)) open.push_back(i);
  }
  if (draws_->draws > 0 && !draws_->first_degree.empty()) {
    const Eigen::Index f = static_cast<Eigen::Index>(draws_->first_degree.size());
    near_.resize(draws_->draws);
    Eigen::VectorXd c(f);
    for (Eigen::Index i : open) {
      for (Eigen::Index j = 0; j < f; ++j) c[j] = coeffs(i, draws_->first_degree[static_cast<std::size_t>(j)]);
      firstDegreeValues(draws_->first.data(), draws_->draws, c.data(), f, coeffs(i, 0), near_.data());
      h->mass_outside_support[i] = massOutside(coeffs, i, near_.data());
    }
  } else {
    for (Eigen::Index i : open) h->mass_outside_support[i] = massOutside(coeffs, i);
  }
  fullProducts(coeffs, h->mass_outside_support);
  h->support_exceeded = (h->mass_outside_support.array() > settings_.support_mass_limit).any();
}

HealthStatus HealthMonitor::assess(const UpdateDiagnostics& update, const ForecastReport& forecast,
                                   const Eigen::MatrixXd& coeffs) {
  HealthStatus h;
  h.forecast_failed = !forecast.ok;
  h.loo_error = forecast.loo_error;
  h.loo_exceeded = h.loo_error.size() > 0 && h.loo_error.maxCoeff() > settings_.loo_warning;
  h.non_finite = !update.finite || !coeffs.allFinite();
  if (update.channels > 0 && !h.non_finite) {
    h.nis = update.nis;
    h.nis_lower = nisBound(false, update.channels);
    h.nis_upper = nisBound(true, update.channels);
    h.nis_outside = h.nis < h.nis_lower || h.nis > h.nis_upper;
    window_.emplace_back(update.nis, update.channels);
    while (static_cast<int>(window_.size()) > settings_.nis_window) window_.pop_front();
  }
  if (!window_.empty()) {
    double sum = 0.0;
    int dof = 0;
    for (const auto& [nis, k] : window_) {
      sum += nis;
      dof += k;
    }
    const double count = static_cast<double>(window_.size());
    h.nis_window_mean = sum / count;
    h.window_lower = nisBound(false, dof) / count;
    h.window_upper = nisBound(true, dof) / count;
    // Judge only a full window: a few samples say little about calibration.
    h.nis_window_outside = static_cast<int>(window_.size()) == settings_.nis_window &&
                           (h.nis_window_mean < h.window_lower || h.nis_window_mean > h.window_upper);
  }
  if (settings_.support_every > 0 && ++assessed_ % settings_.support_every == 0) {
    assessSupport(coeffs, &h);
  }
  if (!h.non_finite) {
    const Eigen::VectorXd mean = pcMean(coeffs), sd = pcStddev(coeffs);
    if (last_mean_.size() == mean.size()) {
      h.band_nested = ((mean - sd).array() >= (last_mean_ - last_std_).array() - 1e-15).all() &&
                      ((mean + sd).array() <= (last_mean_ + last_std_).array() + 1e-15).all();
    }
    last_mean_ = mean;
    last_std_ = sd;
  }
  return h;
}
Eigen::VectorXd coherenceDisagreement(const Eigen::VectorXd& mean_full,
                                      const Eigen::VectorXd& std_full,
                                      const Eigen::VectorXd& mean_decimated,
                                      const Eigen::VectorXd& std_decimated) {
  return ((mean_full - mean_decimated).array().abs() /
          (std_full.array().square() + std_decimated.array().square()).sqrt())
      .matrix();
}

}  // namespace pc_ekf
