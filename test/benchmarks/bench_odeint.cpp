// Boost.Odeint against the hand-written Runge-Kutta (model/integrator.cpp) on
// the filter's forecast: the paper's 30 collocation points, structure-of-arrays
// state (points x states, the model's vectorised right-hand side), the N = 100
// sample intervals of 0.03 s, each split at the road's kinks into uniform
// steps exactly as integrate() splits it. Odeint's fixed-step rk4 at 1 ms and
// dopri5 at 3 ms (used as a plain stepper: no error control, FSAL kept within
// an interval) with vector_space_algebra on Eigen arrays. Reported: CPU time
// per 0.03 s interval (best of several passes) and the largest difference of
// the sampled states to the hand-written stepper's, relative to each state's
// range (the same method and steps: round-off only).
#include <boost/numeric/odeint.hpp>
#include <boost/numeric/odeint/external/eigen/eigen.hpp>

#include "bench_support.h"
#include "pc_ekf/model/integrator.h"

namespace pc_ekf::bench {
namespace {

namespace odeint = boost::numeric::odeint;
using State = Eigen::ArrayXXd;  // points x states
using Rk4 = odeint::runge_kutta4<State, double, State, double, odeint::vector_space_algebra>;
using Dopri5 =
    odeint::runge_kutta_dopri5<State, double, State, double, odeint::vector_space_algebra>;

struct Forecast {
  Scenario scenario = makeScenario(paperConfig(100));
  std::shared_ptr<const ModelBatch> batch;
  Forecast() {
    const PcPropagator& p = *scenario.propagator;
    batch = scenario.model->prepare(
        p.parametersAtPoints(p.priorState().bottomRows(p.parameterCount()), nullptr));
  }
};

const Forecast& forecast() {
  static const Forecast f;
  return f;
}

// integrate()'s segments: kinks strictly inside (t0, t1), uniform steps of at
// most max_step in each.
struct Segment {
  double start, end;
  long steps;
};
std::vector<Segment> segments(const MechanicalModel& model, double t0, double t1, double max_step) {
  const double tol = 1e-12 * std::max(1.0, std::max(std::abs(t0), std::abs(t1)));
  std::vector<double> ends = model.breakpoints(t0, t1);
  std::sort(ends.begin(), ends.end());
  ends.erase(std::remove_if(ends.begin(), ends.end(),
                            [&](double b) { return !(b > t0 + tol && b < t1 - tol); }),
             ends.end());
  ends.push_back(t1);
  std::vector<Segment> out;
  double start = t0;
  for (double end : ends) {
    if (end - start <= tol) continue;
    out.push_back({start, end, std::max(1L, static_cast<long>(std::ceil((end - start) / max_step - 1e-9)))});
    start = end;
  }
  return out;
}

// The sampled SoA states of the record: (100 * points) x states.
using Stepping = std::function<void(State& y, double t0, double t1)>;
Eigen::ArrayXXd run(const Forecast& f, const Stepping& step) {
  const int n = f.scenario.config.sampling.samples;
  State y = f.batch->initialState().transpose();
  Eigen::ArrayXXd out(n * y.rows(), y.cols());
  double t = 0.0;
  for (int k = 0; k < n; ++k) {
    const double t1 = f.scenario.series[k].time;
    step(y, t, t1);
    t = t1;
    out.middleRows(k * y.rows(), y.rows()) = y;
  }
  return out;
}

Stepping handWritten(const Forecast& f, IntegratorSettings settings) {
  return [&f, settings](State& y, double t0, double t1) {
    Eigen::ArrayXXd x = y.transpose();
    integrate(*f.scenario.model, *f.batch, t0, t1, x, settings);
    y = x.transpose();
  };
}

// dopri5 (first same as last) keeps f of its last state: forget it at the
// start of an interval, as integrate() does; rk4 keeps nothing.
template <typename Stepper>
auto restart(Stepper& s, int) -> decltype(s.reset(), void()) {
  s.reset();
}
template <typename Stepper>
void restart(Stepper&, long) {}

template <typename Stepper>
Stepping withOdeint(const Forecast& f, double max_step) {
  return [&f, max_step](State& y, double t0, double t1) {
    const ModelBatch& batch = *f.batch;
    const auto rhs = [&batch](const State& x, State& dxdt, double t) {
      batch.derivativesTransposed(t, x, dxdt);
    };
    thread_local Stepper stepper;
    restart(stepper, 0);
    for (const Segment& s : segments(*f.scenario.model, t0, t1, max_step)) {
      const double h = (s.end - s.start) / static_cast<double>(s.steps);
      for (long i = 0; i < s.steps; ++i) {
        const double t = s.start + static_cast<double>(i) * h;
        stepper.do_step(rhs, y, t, i + 1 == s.steps ? s.end - t : h);  // land on the kink
      }
    }
  };
}

// range 0: 0 = hand-written, 1 = odeint; range 1: IntegrationMethod (0 rk4 at
// 1 ms, 1 dp5 at 3 ms).
void BM_Integrator(benchmark::State& state) {
  const Forecast& f = forecast();
  const bool odeint_stepper = state.range(0) == 1;
  const auto method = static_cast<IntegrationMethod>(state.range(1));
  const double max_step = method == IntegrationMethod::kRk4 ? 1e-3 : 3e-3;
  const Stepping reference_step = handWritten(f, {max_step, method});
  const Stepping step = !odeint_stepper ? reference_step
                        : method == IntegrationMethod::kRk4 ? withOdeint<Rk4>(f, max_step)
                                                            : withOdeint<Dopri5>(f, max_step);
  Eigen::ArrayXXd z;
  for (auto _ : state) z = run(f, step);
  const Eigen::ArrayXXd reference = run(f, reference_step);
  const Eigen::ArrayXd range = reference.abs().colwise().maxCoeff().transpose();
  double worst = 0.0;
  for (Eigen::Index c = 0; c < z.cols(); ++c) {
    if (range[c] > 0) worst = std::max(worst, (z.col(c) - reference.col(c)).abs().maxCoeff() / range[c]);
  }
  const double cpu = bestOf(10, [&] { z = run(f, step); });
  state.counters["us_per_interval"] = 1e6 * cpu / f.scenario.config.sampling.samples;
  state.counters["max_difference"] = worst;
  state.SetLabel(std::string(odeint_stepper ? "odeint " : "hand-written ") +
                 (method == IntegrationMethod::kRk4 ? "rk4 1 ms" : "dp5 3 ms"));
}
BENCHMARK(BM_Integrator)
    ->ArgNames({"odeint", "dp5"})
    ->ArgsProduct({{0, 1}, {0, 1}})
    ->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace pc_ekf::bench

BENCHMARK_MAIN();
