// The safeguards' own rates as health checks (docs/method.md §5.9): the
// fraction of samples the innovation gate refused, the damped updates, the
// re-opens per second and the samples with PDF mass outside the prior
// support. Each has an expected rate under the model; a count beyond the
// one-sided binomial (per sample) or Poisson (per second) bound at the health
// confidence, over the last `window` seconds or over the run, flags it. A
// safeguard then cannot make the data it refuses or absorbs disappear from
// `healthy`.
#pragma once

#include <deque>
#include <string>
#include <vector>

namespace pc_ekf {

struct RateSettings {
  double confidence = 0.99;  // health.nis_confidence: flag when P(X >= count) < 1 - confidence
  double window = 10.0;      // s, health.rate_window
  // Expected fraction of samples the gate refuses: health.innovation_gate
  // (its tail probability under the model; 0 = gate off).
  double gate_probability = 0.0;
  // Allowed fractions of damped updates and of samples with support mass
  // above the limit (no clean null rate; rateSettings: 1 - confidence and
  // 0.1, docs/method.md §5.9).
  double damp_fraction = 0.01;
  double support_fraction = 0.01;
  double reopen_rate = 1.0 / 60.0;  // per s: 1 / health.reopen_interval (load changes)
};

// One rate over one span (the window or the run).
struct RateCheck {
  long count = 0;         // events
  long trials = 0;        // samples judged (binomial checks)
  double exposure = 0.0;  // s (Poisson check)
  double expected = 0.0;  // expected count under the model
  double tail = 1.0;      // P(X >= count) under the model
  bool flagged = false;   // tail < 1 - confidence
};

struct SafeguardRate {
  RateCheck window, run;
  bool flagged() const { return window.flagged || run.flagged; }
};

struct SafeguardRates {
  bool available = false;  // false: no sample yet (or a method without these safeguards)
  SafeguardRate gated, damped, reopened, support;
  // Drives health: the gate, damping and re-open rates. The support rate is
  // reported (warning only): under PC truncation an honest, covered estimate
  // spills past the support on up to 59 % of its samples (docs/method.md §5.9).
  bool flagged() const { return gated.flagged() || damped.flagged() || reopened.flagged(); }
  std::vector<std::string> warnings() const;
};

// P(X >= k) for X ~ Binomial(n, p) and X ~ Poisson(mu) (1 for k <= 0).
double binomialUpperTail(long k, long n, double p);
double poissonUpperTail(long k, double mu);

struct SampleVerdict {
  bool gated = false, damped = false;
};

class SafeguardRateMonitor {
 public:
  explicit SafeguardRateMonitor(const RateSettings& settings = RateSettings());
  // Forgets every sample; the run's exposure starts at `start_time`.
  void reset(double start_time);
  // One processed sample. support: 1 = mass above the limit, 0 = not, -1 = not assessed.
  // reopen_chance: the probability that the re-open rule fired at this sample
  // under the model (chanceReopenPerSample; 0 without re-opens), expected on
  // top of the load changes.
  SafeguardRates add(double time, bool gated, bool damped, bool reopened, int support,
                     double reopen_chance = 0.0);
  long samples() const { return run_.samples; }
  const RateSettings& settings() const { return settings_; }
  // The last verdicts.size() samples were assimilated again (a load change
  // rewound to where it began: reopen mode load): their gated and damped
  // counts become the new verdicts' (oldest first). Returns the change in
  // the gated count.
  int revise(const std::vector<SampleVerdict>& verdicts);

 private:
  struct Counts {
    long samples = 0, gated = 0, damped = 0, reopened = 0, support_trials = 0, support = 0;
    double reopen_chance = 0.0;  // expected chance re-opens
    void add(int sign, bool g, bool d, bool r, int s, double chance);
  };
  struct Event {
    double time;
    bool gated, damped, reopened;
    int support;
    double reopen_chance;
  };
  RateCheck binomial(long count, long trials, double p) const;
  RateCheck poisson(long count, double exposure, double rate, double chance) const;

  RateSettings settings_;
  double start_ = 0.0;
  std::deque<Event> events_;  // the window's samples
  Counts window_, run_;
};

}  // namespace pc_ekf
