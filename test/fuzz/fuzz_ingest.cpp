// Fuzz target: the core's measurement-ingest API (OneStepFilter::process).
//
// Built once: the one-step filter of config/speed_bump.yaml at reduced cost
// (pc.order 2, collocation.points 8, integration.max_step 0.01), with the
// square-root and with the paper update. Per input the chosen filter is reset
// and fed up to kMaxSamples Measurements decoded from the bytes: arbitrary
// doubles (NaN, +-Inf, denormals, +-max, raw bit patterns), arbitrary channel
// lists (valid masks, or raw lists with duplicates, disorder, out-of-range
// indices, length mismatches), arbitrary times (small steps, equal times,
// raw doubles: backwards, huge, NaN).
//
// Contract checked (OneStepFilter, one_step_filter.h):
//  - the only allowed exception is std::invalid_argument, and a rejected
//    sample leaves the filter untouched (state bits, time, sample count);
//  - after an accepted sample the time and count advance, and the state is
//    finite unless the StepResult's health flags non_finite or forecast_failed
//    (a healthy result always has finite mean/std);
//  - no crash, sanitizer report or hang.
//
// Harness limits (to keep one run short; NOT limits of the product): a sample
// stamped more than kMaxAdvance = 10 s after the filter's time is skipped,
// and at most kMaxHorizon = 12 s of model time (4x the paper's 3 s run) are
// integrated per input; longer advances are tested by the unit tests.
#include <fuzzer/FuzzedDataProvider.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "pc_ekf/filter/one_step_filter.h"
#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/io/estimator_config.h"

namespace {

constexpr int kMaxSamples = 48;
constexpr double kMaxAdvance = 10.0;
constexpr double kMaxHorizon = 12.0;

struct Filters {
  std::unique_ptr<pc_ekf::OneStepFilter> square_root, paper;
};

Filters makeFilters() {
  pc_ekf::EstimatorConfig c =
      pc_ekf::loadConfigFile(std::string(PC_EKF_SOURCE_DIR) + "/config/speed_bump.yaml");
  c.pc_order = 2;
  c.collocation.points = 8;
  c.integration.max_step = 0.01;
  const auto model = pc_ekf::makeModel(c, pc_ekf::makeRoad(c));
  const auto propagator = pc_ekf::makePropagator(c, model);
  Filters f;
  pc_ekf::OneStepSettings s = pc_ekf::makeOneStepSettings(c);
  s.rule = pc_ekf::UpdateRule::kSquareRoot;
  f.square_root = std::make_unique<pc_ekf::OneStepFilter>(propagator, s);
  s.rule = pc_ekf::UpdateRule::kPaper;
  f.paper = std::make_unique<pc_ekf::OneStepFilter>(propagator, s);
  return f;
}

void check(bool ok) {
  if (!ok) std::abort();
}

// PC_EKF_FUZZ_VERBOSE=1 prints each decoded sample and its outcome (to debug
// a crash input: ./fuzz_ingest crash-...).
const bool kVerbose = std::getenv("PC_EKF_FUZZ_VERBOSE") != nullptr;

void print(const pc_ekf::Measurement& m, const std::string& outcome,
           const pc_ekf::StepResult* r = nullptr) {
  if (!kVerbose) return;
  std::cerr << "t=" << m.time << " channels=[";
  for (int c : m.channels) std::cerr << c << ' ';
  std::cerr << "] values=[" << m.values.transpose() << "] -> " << outcome;
  if (r) {
    std::cerr << "; mean " << r->mean.transpose() << ", std " << r->stddev.transpose();
    for (const auto& w : r->health.warnings()) std::cerr << "; " << w;
  }
  std::cerr << '\n';
}

double rawDouble(FuzzedDataProvider& in) {
  std::uint64_t bits = in.ConsumeIntegral<std::uint64_t>();
  double v;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

double value(FuzzedDataProvider& in) {
  static const double kSpecial[] = {
      std::numeric_limits<double>::quiet_NaN(),
      std::numeric_limits<double>::infinity(),
      -std::numeric_limits<double>::infinity(),
      std::numeric_limits<double>::denorm_min(),
      -std::numeric_limits<double>::denorm_min(),
      std::numeric_limits<double>::min(),
      std::numeric_limits<double>::max(),
      std::numeric_limits<double>::lowest(),
      0.0,
      -0.0,
      1e-12,
      1e150,
      -1e150,
      1e300,
  };
  const std::uint8_t kind = in.ConsumeIntegral<std::uint8_t>();
  if (kind < 128) return in.ConsumeIntegral<std::int16_t>() * 1e-5;  // plausible: +-0.33 m(/s)
  if (kind < 192) return kSpecial[(kind - 128) % (sizeof kSpecial / sizeof kSpecial[0])];
  return rawDouble(in);
}

double stamp(FuzzedDataProvider& in, double now) {
  switch (in.ConsumeIntegralInRange<int>(0, 4)) {
    case 0: return now + in.ConsumeIntegral<std::uint16_t>() * 1e-4;  // 0 .. 6.5 s ahead
    case 1: return now;                                               // zero interval
    case 2: return now - in.ConsumeIntegral<std::uint16_t>() * 1e-4;  // backwards
    case 3: return rawDouble(in);                                     // anything
    default: return now + value(in);
  }
}

pc_ekf::Measurement measurement(FuzzedDataProvider& in, double now) {
  pc_ekf::Measurement m;
  m.time = stamp(in, now);
  const std::uint8_t mode = in.ConsumeIntegral<std::uint8_t>();
  if (mode & 0x80) {  // raw channel list: duplicates, disorder, out of range
    const int n = in.ConsumeIntegralInRange<int>(0, 6);
    for (int i = 0; i < n; ++i) m.channels.push_back(in.ConsumeIntegralInRange<int>(-2, 5));
  } else {  // a valid mask
    for (int c = 0; c < 4; ++c) {
      if (mode & (1 << c)) m.channels.push_back(c);
    }
  }
  Eigen::Index count = static_cast<Eigen::Index>(m.channels.size());
  if (mode & 0x40) count = in.ConsumeIntegralInRange<int>(0, 6);  // maybe a length mismatch
  m.values.resize(count);
  for (Eigen::Index i = 0; i < count; ++i) m.values[i] = value(in);
  return m;
}

// Bitwise equality (NaN-aware): a rejected sample must leave the state as it was.
bool sameBits(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static Filters filters = makeFilters();
  FuzzedDataProvider in(data, size);
  pc_ekf::OneStepFilter& filter = in.ConsumeBool() ? *filters.paper : *filters.square_root;
  filter.reset();
  double horizon = 0.0;
  for (int k = 0; k < kMaxSamples && in.remaining_bytes() > 0; ++k) {
    const pc_ekf::Measurement m = measurement(in, filter.time());
    const double advance = m.time - filter.time();
    if (advance > kMaxAdvance || horizon + advance > kMaxHorizon) {  // harness limit
      print(m, "skipped (harness time cap)");
      continue;
    }
    const Eigen::MatrixXd before = filter.state();
    const double t_before = filter.time();
    const int n_before = filter.samples();
    pc_ekf::StepResult r;
    try {
      r = filter.process(m);
    } catch (const std::invalid_argument& e) {
      print(m, e.what());
      check(sameBits(filter.state(), before) && filter.time() == t_before &&
            filter.samples() == n_before);
      continue;
    }
    horizon += advance;
    print(m, r.health.healthy() ? "accepted, healthy" : "accepted, unhealthy", &r);
    check(filter.time() == m.time && filter.samples() == n_before + 1 && r.index == n_before + 1);
    const bool flagged = r.health.non_finite || r.health.forecast_failed;
    check(filter.state().allFinite() || flagged);
    if (r.health.healthy()) check(r.mean.allFinite() && r.stddev.allFinite());
  }
  return 0;
}
