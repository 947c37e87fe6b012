// Explicit Runge-Kutta between the input's kinks (docs/method.md §1.7, §7).
#include "pc_ekf/model/integrator.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace pc_ekf {

std::string toString(IntegrationMethod m) {
  return m == IntegrationMethod::kRk4 ? "rk4" : "dp5";
}

IntegrationMethod integrationMethodFromString(const std::string& name) {
  if (name == "rk4") return IntegrationMethod::kRk4;
  if (name == "dp5") return IntegrationMethod::kDormandPrince5;
  throw std::invalid_argument("integration method '" + name + "' unknown, expected rk4 or dp5");
}

namespace {

// Butcher tableaux. Dormand & Prince (1980), 5th-order weights; the last stage
// is evaluated at the new state, so it is the next step's first (FSAL).
struct Tableau {
  int stages;
  double c[7];
  double a[7][6];
  double b[6];
  bool first_same_as_last;
};

constexpr Tableau kRk4Tableau{
    4,
    {0.0, 0.5, 0.5, 1.0},
    {{}, {0.5}, {0.0, 0.5}, {0.0, 0.0, 1.0}},
    {1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0},
    false};

constexpr Tableau kDp5Tableau{
    6,
    {0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0},
    {{},
     {1.0 / 5.0},
     {3.0 / 40.0, 9.0 / 40.0},
     {44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0},
     {19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0},
     {9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0}},
    {35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0},
    true};

// out = y + sum_j w[j] k[j] in one pass, for T terms.
template <int T>
__attribute__((always_inline)) inline void combineTerms(double* __restrict out,
                                                        const double* __restrict y,
                                                        const double* w, const double* const* k,
                                                        Eigen::Index size) {
  double weight[T];
  const double* __restrict term[T];
  for (int j = 0; j < T; ++j) {
    weight[j] = w[j];
    term[j] = k[j];
  }
  for (Eigen::Index i = 0; i < size; ++i) {
    double acc = y[i];
    for (int j = 0; j < T; ++j) acc += weight[j] * term[j][i];
    out[i] = acc;
  }
}

// out = y + sum_j w[j] k[j] over the terms with a nonzero weight, elementwise
// in a fixed order (so each point's value does not depend on the batch).
// Compiled for x86-64-v3 and the baseline.
__attribute__((target_clones("arch=x86-64-v3", "default"))) void combine(
    double* __restrict out, const double* __restrict y, const double* w,
    const double* const* k, int terms, Eigen::Index size) {
  double weight[8];
  const double* term[8];
  int used = 0;
  for (int j = 0; j < terms && used < 8; ++j) {
    if (w[j] == 0.0) continue;
    weight[used] = w[j];
    term[used++] = k[j];
  }
  switch (used) {
    case 0: std::copy(y, y + size, out); break;
    case 1: combineTerms<1>(out, y, weight, term, size); break;
    case 2: combineTerms<2>(out, y, weight, term, size); break;
    case 3: combineTerms<3>(out, y, weight, term, size); break;
    case 4: combineTerms<4>(out, y, weight, term, size); break;
    case 5: combineTerms<5>(out, y, weight, term, size); break;
    default: combineTerms<6>(out, y, weight, term, size); break;
  }
}

// Stage buffers reused across calls on the same thread: integrate() runs once per
// collocation forecast, so per-call allocation would dominate small intervals.
struct RkWork {
  Eigen::ArrayXXd y, stage, next;
  Eigen::ArrayXXd k[7];
  void resize(Eigen::Index rows, Eigen::Index cols) {
    y.resize(rows, cols);
    stage.resize(rows, cols);
    next.resize(rows, cols);
    for (auto& a : k) a.resize(rows, cols);
  }
};

// One classical RK4 step in the model's own layout (models without the
// structure-of-arrays form, e.g. the test models).
void rk4Step(const ModelBatch& batch, double t, double h, Eigen::ArrayXXd& y, RkWork& w) {
  const double half = 0.5 * h;
  batch.derivatives(t, y, w.k[0]);
  w.stage = y + half * w.k[0];
  batch.derivatives(t + half, w.stage, w.k[1]);
  w.stage = y + half * w.k[1];
  batch.derivatives(t + half, w.stage, w.k[2]);
  w.stage = y + h * w.k[2];
  batch.derivatives(t + h, w.stage, w.k[3]);
  y += (h / 6.0) * (w.k[0] + 2.0 * (w.k[1] + w.k[2]) + w.k[3]);
}

// Any tableau; `f(t, y, dydt)` evaluates the right-hand side in y's layout.
// With first_same_as_last, k[0] must hold f(t, y) on entry and holds f at the
// new state on exit when `need_last` (the next step's first stage).
template <typename Rhs>
void tableauStep(const Tableau& tab, const Rhs& f, double t, double h, Eigen::ArrayXXd& y,
                 RkWork& w, bool need_last) {
  // y is w.y (structure-of-arrays path) or the caller's array: the new state
  // is built in w.next and swapped in when y belongs to the work area.
  const Eigen::Index size = y.size();
  const double* k_ptr[7];
  double weight[7];
  for (int i = 0; i < tab.stages; ++i) k_ptr[i] = w.k[i].data();
  if (!tab.first_same_as_last) f(t, y, w.k[0]);
  for (int i = 1; i < tab.stages; ++i) {
    for (int j = 0; j < i; ++j) weight[j] = h * tab.a[i][j];
    combine(w.stage.data(), y.data(), weight, k_ptr, i, size);
    f(t + tab.c[i] * h, w.stage, w.k[i]);
  }
  for (int j = 0; j < tab.stages; ++j) weight[j] = h * tab.b[j];
  combine(w.next.data(), y.data(), weight, k_ptr, tab.stages, size);
  if (&y == &w.y) {
    y.swap(w.next);
  } else {
    y = w.next;
  }
  if (tab.first_same_as_last && need_last) f(t + h, y, w.k[0]);
}

struct Segment {
  double start, end;
  long steps;
};

template <typename Step>
void integrateSegments(const std::vector<Segment>& segments, const Step& step_fn,
                       Eigen::ArrayXXd& y, RkWork& work) {
  for (std::size_t s = 0; s < segments.size(); ++s) {
    const Segment& seg = segments[s];
    const double h = (seg.end - seg.start) / static_cast<double>(seg.steps);
    for (long k = 0; k < seg.steps; ++k) {
      const double t = seg.start + static_cast<double>(k) * h;
      const bool last_of_segment = k + 1 == seg.steps;
      const double step = last_of_segment ? seg.end - t : h;  // land exactly on the segment end
      step_fn(t, step, y, work, !(last_of_segment && s + 1 == segments.size()));
    }
  }
}

}  // namespace

namespace {

void integrateDynamic(const MechanicalModel& model, const ModelBatch& batch, double t0, double t1,
                      Eigen::ArrayXXd& y, const IntegratorSettings& settings);

}  // namespace

void integrate(const MechanicalModel& model, const ModelBatch& batch, double t0, double t1,
               Eigen::ArrayXXd& y, const IntegratorSettings& settings) {
  if (!(t1 >= t0)) throw std::invalid_argument("integrate: t1 must be >= t0 (and not NaN)");
  if (!(settings.max_step > 0.0)) throw std::invalid_argument("integrate: max_step must be > 0");
  if (y.rows() != model.stateSize() || y.cols() != batch.pointCount()) {
    throw std::invalid_argument("integrate: y must be stateSize() x pointCount()");
  }
  if (t1 == t0) return;
  const int dynamic = model.dynamicStateSize();
  if (dynamic == y.rows()) {
    integrateDynamic(model, batch, t0, t1, y, settings);
    return;
  }
  if (dynamic == 0) {  // readings only (a road-free model)
    batch.readings(t1, y);
    return;
  }
  // Readings kept as states: advance the dynamic rows, then read at t1.
  thread_local Eigen::ArrayXXd moving;
  moving = y.topRows(dynamic);
  integrateDynamic(model, batch, t0, t1, moving, settings);
  y.topRows(dynamic) = moving;
  batch.readings(t1, y);
}

namespace {

void integrateDynamic(const MechanicalModel& model, const ModelBatch& batch, double t0, double t1,
                      Eigen::ArrayXXd& y, const IntegratorSettings& settings) {

  // Segment ends: breakpoints strictly inside, merging those within round-off of an end.
  const double tol = 1e-12 * std::max(1.0, std::max(std::abs(t0), std::abs(t1)));
  thread_local std::vector<double> ends;
  thread_local std::vector<Segment> segments;
  ends = model.breakpoints(t0, t1);
  std::sort(ends.begin(), ends.end());
  ends.erase(std::remove_if(ends.begin(), ends.end(),
                            [&](double b) { return !(b > t0 + tol && b < t1 - tol); }),
             ends.end());
  ends.push_back(t1);
  segments.clear();
  double start = t0;
  for (double end : ends) {
    if (end - start <= tol) continue;  // duplicate breakpoint
    const double length = end - start;
    // The slack keeps e.g. 0.03 / 1e-3 at 30 steps despite round-off.
    const long n = std::max(1L, static_cast<long>(std::ceil(length / settings.max_step - 1e-9)));
    segments.push_back({start, end, n});
    start = end;
  }
  if (segments.empty()) return;

  thread_local RkWork work;
  const Tableau& tab =
      settings.method == IntegrationMethod::kRk4 ? kRk4Tableau : kDp5Tableau;
  if (batch.hasTransposedDerivatives()) {
    // Structure of arrays: one contiguous column per state variable, so the
    // model's right-hand side vectorises across the points.
    work.resize(y.cols(), y.rows());
    work.y = y.transpose();
    const auto f = [&batch](double t, const Eigen::ArrayXXd& s, Eigen::ArrayXXd& d) {
      batch.derivativesTransposed(t, s, d);
    };
    if (tab.first_same_as_last) f(segments.front().start, work.y, work.k[0]);
    integrateSegments(
        segments,
        [&](double t, double h, Eigen::ArrayXXd& s, RkWork& w, bool need_last) {
          tableauStep(tab, f, t, h, s, w, need_last);
        },
        work.y, work);
    y = work.y.transpose();
  } else if (settings.method == IntegrationMethod::kRk4) {
    work.resize(y.rows(), y.cols());
    integrateSegments(
        segments,
        [&batch](double t, double h, Eigen::ArrayXXd& s, RkWork& w, bool) {
          rk4Step(batch, t, h, s, w);
        },
        y, work);
  } else {
    work.resize(y.rows(), y.cols());
    const auto f = [&batch](double t, const Eigen::ArrayXXd& s, Eigen::ArrayXXd& d) {
      batch.derivatives(t, s, d);
    };
    f(segments.front().start, y, work.k[0]);
    integrateSegments(
        segments,
        [&](double t, double h, Eigen::ArrayXXd& s, RkWork& w, bool need_last) {
          tableauStep(tab, f, t, h, s, w, need_last);
        },
        y, work);
  }
}

}  // namespace

}  // namespace pc_ekf
