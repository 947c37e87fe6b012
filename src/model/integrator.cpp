// Classical RK4 between the input's kinks (SPEC §1.5, §5).
#include "model/integrator.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace pc_ekf {

namespace {

// Stage buffers reused across calls on the same thread: integrate() runs once per
// collocation forecast, so per-call allocation would dominate small intervals.
struct Rk4Work {
  Eigen::ArrayXXd k1, k2, k3, k4, stage;
  void resize(Eigen::Index rows, Eigen::Index cols) {
    for (Eigen::ArrayXXd* a : {&k1, &k2, &k3, &k4, &stage}) a->resize(rows, cols);
  }
};

void rk4Step(const ModelBatch& batch, double t, double h, Eigen::ArrayXXd& y, Rk4Work& w) {
  const double half = 0.5 * h;
  batch.derivatives(t, y, w.k1);
  w.stage = y + half * w.k1;
  batch.derivatives(t + half, w.stage, w.k2);
  w.stage = y + half * w.k2;
  batch.derivatives(t + half, w.stage, w.k3);
  w.stage = y + h * w.k3;
  batch.derivatives(t + h, w.stage, w.k4);
  y += (h / 6.0) * (w.k1 + 2.0 * (w.k2 + w.k3) + w.k4);
}

}  // namespace

void integrate(const MechanicalModel& model, const ModelBatch& batch, double t0, double t1,
               Eigen::ArrayXXd& y, const IntegratorSettings& settings) {
  if (!(t1 >= t0)) throw std::invalid_argument("integrate: t1 must be >= t0 (and not NaN)");
  if (!(settings.max_step > 0.0)) throw std::invalid_argument("integrate: max_step must be > 0");
  if (y.rows() != model.stateSize() || y.cols() != batch.pointCount()) {
    throw std::invalid_argument("integrate: y must be stateSize() x pointCount()");
  }
  if (t1 == t0) return;

  // Segment ends: breakpoints strictly inside, merging those within round-off of an end.
  const double tol = 1e-12 * std::max(1.0, std::max(std::abs(t0), std::abs(t1)));
  std::vector<double> ends = model.breakpoints(t0, t1);
  std::sort(ends.begin(), ends.end());
  ends.erase(std::remove_if(ends.begin(), ends.end(),
                            [&](double b) { return !(b > t0 + tol && b < t1 - tol); }),
             ends.end());
  ends.push_back(t1);

  thread_local Rk4Work work;
  work.resize(y.rows(), y.cols());
  double start = t0;
  for (double end : ends) {
    if (end - start <= tol) continue;  // duplicate breakpoint
    const double length = end - start;
    // The slack keeps e.g. 0.03 / 1e-3 at 30 steps despite round-off.
    const long n = std::max(1L, static_cast<long>(std::ceil(length / settings.max_step - 1e-9)));
    const double h = length / static_cast<double>(n);
    for (long k = 0; k < n; ++k) {
      const double t = start + static_cast<double>(k) * h;
      const double step = (k + 1 == n) ? end - t : h;  // land exactly on the segment end
      rk4Step(batch, t, step, y, work);
    }
    start = end;
  }
}

}  // namespace pc_ekf
