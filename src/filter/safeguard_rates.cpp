#include "pc_ekf/filter/safeguard_rates.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace pc_ekf {
namespace {

// Sums pmf(i) from i = k outwards in the direction `step` (+1 up, -1 down)
// with pmf(i +- 1) = pmf(i) * ratio(i), until the terms no longer count.
template <typename Ratio>
double tailSum(double first, long k, long last, int step, Ratio ratio) {
  double sum = 0.0, term = first;
  for (long i = k;; i += step) {
    sum += term;
    if (i == last) break;
    term *= ratio(i);
    if (term <= 1e-18 * sum || term == 0.0) break;
  }
  return sum;
}

}  // namespace

double binomialUpperTail(long k, long n, double p) {
  if (k <= 0) return 1.0;
  if (k > n || p <= 0.0) return 0.0;
  if (p >= 1.0) return 1.0;
  const double lq = std::log1p(-p), lp = std::log(p);
  const auto pmf = [&](long i) {
    return std::exp(std::lgamma(n + 1.0) - std::lgamma(i + 1.0) - std::lgamma(n - i + 1.0) +
                    static_cast<double>(i) * lp + static_cast<double>(n - i) * lq);
  };
  const double odds = p / (1.0 - p);
  if (static_cast<double>(k) >= static_cast<double>(n) * p) {  // above the mean: sum upwards
    return std::min(1.0, tailSum(pmf(k), k, n, +1, [&](long i) {
                      return static_cast<double>(n - i) / static_cast<double>(i + 1) * odds;
                    }));
  }
  // Below the mean: 1 - P(X <= k - 1), summed downwards.
  const double lower = tailSum(pmf(k - 1), k - 1, 0, -1, [&](long i) {
    return static_cast<double>(i) / static_cast<double>(n - i + 1) / odds;
  });
  return std::max(0.0, 1.0 - lower);
}

double poissonUpperTail(long k, double mu) {
  if (k <= 0) return 1.0;
  if (!(mu > 0.0)) return 0.0;
  const auto pmf = [&](long i) {
    return std::exp(-mu + static_cast<double>(i) * std::log(mu) - std::lgamma(i + 1.0));
  };
  if (static_cast<double>(k) >= mu) {
    return std::min(1.0, tailSum(pmf(k), k, -1, +1,
                                 [&](long i) { return mu / static_cast<double>(i + 1); }));
  }
  const double lower =
      tailSum(pmf(k - 1), k - 1, 0, -1, [&](long i) { return static_cast<double>(i) / mu; });
  return std::max(0.0, 1.0 - lower);
}

namespace {

void describe(std::vector<std::string>& w, const char* what, const SafeguardRate& r,
              bool per_second) {
  if (!r.flagged()) return;
  const RateCheck& c = r.run.flagged ? r.run : r.window;
  std::ostringstream o;
  o.precision(3);
  o << what << ": " << c.count;
  if (per_second) {
    o << " in " << c.exposure << " s";
  } else {
    o << " of " << c.trials << " samples";
  }
  o << (r.run.flagged ? " (run)" : " (window)") << ", " << c.expected
    << " expected under the model (P = " << c.tail << ")";
  w.push_back(o.str());
}

}  // namespace

std::vector<std::string> SafeguardRates::warnings() const {
  std::vector<std::string> w;
  describe(w, "innovation gate rate beyond its bound: samples not used", gated, false);
  describe(w, "damping rate beyond its bound: updates damped", damped, false);
  describe(w, "re-open rate beyond its bound (more than load changes explain): re-opens", reopened,
           true);
  describe(w, "support rate beyond its allowance (warning only): samples with PDF mass outside the support",
           support, false);
  return w;
}

void SafeguardRateMonitor::Counts::add(int sign, bool g, bool d, bool r, int s, double chance) {
  samples += sign;
  reopen_chance += sign * chance;
  gated += sign * g;
  damped += sign * d;
  reopened += sign * r;
  if (s >= 0) {
    support_trials += sign;
    support += sign * s;
  }
}

SafeguardRateMonitor::SafeguardRateMonitor(const RateSettings& settings) : settings_(settings) {}

void SafeguardRateMonitor::reset(double start_time) {
  start_ = start_time;
  events_.clear();
  window_ = Counts();
  run_ = Counts();
}

RateCheck SafeguardRateMonitor::binomial(long count, long trials, double p) const {
  RateCheck c;
  c.count = count;
  c.trials = trials;
  c.expected = static_cast<double>(trials) * p;
  c.tail = binomialUpperTail(count, trials, p);
  c.flagged = c.tail < 1.0 - settings_.confidence;
  return c;
}

RateCheck SafeguardRateMonitor::poisson(long count, double exposure, double rate,
                                        double chance) const {
  RateCheck c;
  c.count = count;
  c.exposure = exposure;
  c.expected = rate * exposure + std::max(0.0, chance);
  c.tail = poissonUpperTail(count, c.expected);
  c.flagged = c.tail < 1.0 - settings_.confidence;
  return c;
}

int SafeguardRateMonitor::revise(const std::vector<SampleVerdict>& verdicts) {
  int change = 0;
  auto e = events_.rbegin();
  for (auto v = verdicts.rbegin(); v != verdicts.rend() && e != events_.rend(); ++v, ++e) {
    const int gated = static_cast<int>(v->gated) - static_cast<int>(e->gated);
    const int damped = static_cast<int>(v->damped) - static_cast<int>(e->damped);
    window_.gated += gated;
    run_.gated += gated;
    window_.damped += damped;
    run_.damped += damped;
    change += gated;
    e->gated = v->gated;
    e->damped = v->damped;
  }
  return change;
}

SafeguardRates SafeguardRateMonitor::add(double time, bool gated, bool damped, bool reopened,
                                         int support, double reopen_chance) {
  events_.push_back({time, gated, damped, reopened, support, reopen_chance});
  window_.add(+1, gated, damped, reopened, support, reopen_chance);
  run_.add(+1, gated, damped, reopened, support, reopen_chance);
  while (!events_.empty() && events_.front().time <= time - settings_.window) {
    const Event& e = events_.front();
    window_.add(-1, e.gated, e.damped, e.reopened, e.support, e.reopen_chance);
    events_.pop_front();
  }
  const double run_exposure = std::max(0.0, time - start_);
  const double window_exposure = std::min(settings_.window, run_exposure);
  SafeguardRates r;
  r.available = true;
  const RateSettings& s = settings_;
  r.gated = {binomial(window_.gated, window_.samples, s.gate_probability),
             binomial(run_.gated, run_.samples, s.gate_probability)};
  r.damped = {binomial(window_.damped, window_.samples, s.damp_fraction),
              binomial(run_.damped, run_.samples, s.damp_fraction)};
  r.reopened = {poisson(window_.reopened, window_exposure, s.reopen_rate, window_.reopen_chance),
                poisson(run_.reopened, run_exposure, s.reopen_rate, run_.reopen_chance)};
  r.support = {binomial(window_.support, window_.support_trials, s.support_fraction),
               binomial(run_.support, run_.support_trials, s.support_fraction)};
  return r;
}

}  // namespace pc_ekf
