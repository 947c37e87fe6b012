// Static equilibrium of the roll-plane model (SPEC §1.3).
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "model/roll_plane_model.h"

namespace pc_ekf {

namespace {

// Solves k d + k3 d^3 = w. For k > 0, k3 >= 0 the law is odd, increasing and convex
// for d > 0, so Newton from an over-estimate decreases monotonically to the root.
double springCompression(double k, double k3, double w) {
  const double a = std::abs(w);
  double d = a / k;
  if (k3 > 0.0) d = std::min(d, std::cbrt(a / k3));  // both over-estimate the root
  for (int it = 0; it < 100 && std::isfinite(d); ++it) {
    const double step = (k * d + k3 * d * d * d - a) / (k + 3.0 * k3 * d * d);
    d -= step;
    if (std::abs(step) <= 1e-15 * std::abs(d) || step == 0.0) return std::copysign(d, w);
  }
  std::ostringstream os;
  os << "static equilibrium: Newton did not converge for spring k = " << k << ", k3 = " << k3
     << ", load = " << w;
  throw std::runtime_error(os.str());
}

}  // namespace

StaticEquilibrium solveStaticEquilibrium(const VehicleParameters& p) {
  const double total = p.bar_mass + p.added_mass;
  const double length = p.bar_length;
  StaticEquilibrium e;
  e.combined_cg = (p.added_mass * p.added_mass_position + p.bar_mass * 0.5 * length) / total;
  const double weight = total * p.gravity;
  // W_1 from (L - D) rather than weight - W_2: same value, exactly symmetric at D = L/2.
  e.load[0] = weight * (length - e.combined_cg) / length;
  e.load[1] = weight * e.combined_cg / length;
  for (int i = 0; i < 2; ++i) {
    e.spring_compression[i] = springCompression(p.spring_linear[i], p.spring_cubic[i], e.load[i]);
    const double tyre = (e.load[i] + p.unsprung_mass[i] * p.gravity) / p.tyre_stiffness[i];
    e.height[i] = -(e.spring_compression[i] + tyre);
  }
  e.roll_angle = std::atan((e.height[1] - e.height[0]) / length);
  if (!std::isfinite(e.roll_angle)) {
    throw std::runtime_error("static equilibrium: non-finite roll angle");
  }
  return e;
}

}  // namespace pc_ekf
