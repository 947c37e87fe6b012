// Per-update health checks (docs/method.md §5): NIS against two-sided chi-square
// bounds and its windowed average, PDF mass outside the prior support,
// non-finite values, and the paper's nested-band criterion (informational
// only: the exact posterior violates it at most steps).
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <deque>
#include <string>
#include <memory>
#include <vector>

#include "pc_ekf/filter/kalman_update.h"
#include "pc_ekf/filter/pc_propagator.h"
#include "pc_ekf/filter/safeguard_rates.h"

namespace pc_ekf {

// The windows and the confidence the checks judge by: keys of health:
// (estimator_config.h reads them into this struct, with the section's others).
struct HealthLimits {
  int nis_window = 10;
  double nis_confidence = 0.99;  // two-sided
  // The safeguards' rates (SafeguardRates, docs/method.md §5.9): the window
  // in s, and the expected time between load changes (re-opens) in s.
  double rate_window = 10.0;
  double reopen_interval = 60.0;
};

struct HealthSettings : HealthLimits {
  int support_draws = 2000;      // germ samples for the outside-support mass
  // assess() computes the mass outside the support at every k-th sample (0:
  // never); at the others it leaves mass_outside_support empty and
  // support_exceeded false, and a caller that needs them (estimate_offline:
  // the last sample) asks with assessSupport(). The support rate (warning
  // only) counts the assessed samples. Nothing else depends on them.
  int support_every = 1;
  double support_mass_limit = 0.05;
  std::uint64_t seed = 11;
  // Relative leave-one-out error of the forecast's projection above which a
  // channel is flagged (warning: the expansion misses part of the response).
  double loo_warning = 0.1;
};

struct HealthStatus {
  double nis = 0.0;
  double nis_lower = 0.0, nis_upper = 0.0;
  bool nis_outside = false;  // this sample (expected in 1 - confidence of samples)
  double nis_window_mean = 0.0;
  double window_lower = 0.0, window_upper = 0.0;
  bool nis_window_outside = false;  // drives health
  Eigen::VectorXd mass_outside_support;  // per parameter (empty: not assessed)
  bool support_exceeded = false;         // any mass above support_mass_limit (warning)
  bool non_finite = false;               // drives health
  bool forecast_failed = false;          // drives health
  bool band_nested = true;               // informational only
  bool gated = false;     // NIS above the innovation gate: sample not used
  bool damped = false;    // update scaled down to keep the means in the support; drives health
  bool reopened = false;  // uncertainty re-opened after a persistent violation
  Eigen::VectorXd loo_error;  // per channel (ForecastReport::loo_error; empty: unavailable)
  bool loo_exceeded = false;  // some channel above loo_warning (warning only)
  // One-step: the safeguards' rates up to this sample (window and run); a
  // rate beyond its bound drives health.
  SafeguardRates rates;
  bool healthy() const {
    return !non_finite && !forecast_failed && !nis_window_outside && !damped && !reopened &&
           !rates.flagged();
  }
  std::vector<std::string> warnings() const;
};

// The rate checks' settings from the health settings and the gate's tail
// probability (docs/method.md §5.9).
RateSettings rateSettings(const HealthSettings& health, double innovation_gate);

// Quantile of the chi-square distribution with `dof` degrees of freedom.
double chiSquareQuantile(double probability, double dof);

class HealthMonitor {
 public:
  // The basis at the fixed germ draws of the support check.
  struct SupportDraws {
    static constexpr int kPad = 16;  // zero rows past the draws (gemvOrderValues reads ahead)
    Eigen::Index draws = 0;
    Eigen::MatrixXd padded;          // (draws + kPad) x S: psi_j at the draws, then zeros
    Eigen::VectorXd max_abs;         // per term, max over the draws of |psi_j|
    std::vector<Eigen::Index> first_degree;  // the terms of total degree 1
    Eigen::MatrixXd first;                   // draws x |first_degree|: their columns, together
  };

  HealthMonitor(const PcPropagator& propagator, const HealthSettings& settings);
  HealthStatus assess(const UpdateDiagnostics& update, const ForecastReport& forecast,
                      const Eigen::MatrixXd& parameter_coeffs);
  // The mass outside the support and support_exceeded, into h (its other
  // fields untouched); nothing when h says the state is not finite.
  void assessSupport(const Eigen::MatrixXd& parameter_coeffs, HealthStatus* h);
  void reset();

 private:
  // Cached chi-square bounds by degrees of freedom (quantiles are iterative).
  double nisBound(bool upper, int dof);
  // Fraction of the germ draws whose value lies outside [lower_i, upper_i];
  // -1 when most draws need the whole product (fullProducts fills those in).
  // near: the mean plus first-degree terms at the draws (else computed here).
  double massOutside(const Eigen::MatrixXd& coeffs, Eigen::Index i, const double* near = nullptr);
  // The bound on |value - mean| over the draws (and its round-off, *slack),
  // and whether every draw's value is inside the support by it alone.
  double spreadBound(const Eigen::MatrixXd& coeffs, Eigen::Index i, double* slack) const;
  bool boundedInside(const Eigen::MatrixXd& coeffs, Eigen::Index i) const;
  void fullProducts(const Eigen::MatrixXd& coeffs, Eigen::VectorXd& mass);

  HealthSettings settings_;
  std::shared_ptr<const SupportDraws> draws_;  // shared by monitors of the same basis
  Eigen::VectorXd near_;                       // support_draws: mean + first-degree terms (reused)
  Eigen::RowVectorXd row_;                     // one quantity's coefficients, contiguous (reused)
  std::vector<Eigen::Index> candidates_;       // draws the bounds do not show inside (reused)
  Eigen::VectorXd lower_, upper_;
  std::vector<double> bound_cache_[2];  // [lower, upper][dof], NaN = not yet computed
  std::deque<std::pair<double, int>> window_;  // (nis, channels)
  long assessed_ = 0;                          // samples seen by assess() (support_every)
  Eigen::VectorXd last_mean_, last_std_;
};

// Multi-rate coherence (docs/method.md §5.2): |m_full - m_dec| / sqrt(s_full^2 + s_dec^2).
Eigen::VectorXd coherenceDisagreement(const Eigen::VectorXd& mean_full,
                                      const Eigen::VectorXd& std_full,
                                      const Eigen::VectorXd& mean_decimated,
                                      const Eigen::VectorXd& std_decimated);

}  // namespace pc_ekf
