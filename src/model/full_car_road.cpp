#include "pc_ekf/model/full_car_road.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace pc_ekf {

FullCarBumpRoad::FullCarBumpRoad(const FullCarBumpSettings& s) : s_(s) {
  const double values[] = {s.speed_kmh,   s.height_left,      s.height_right, s.ramp_up_length,
                           s.flat_length, s.ramp_down_length, s.right_offset, s.wheelbase};
  for (double v : values) {
    if (!std::isfinite(v)) throw std::invalid_argument("FullCarBumpRoad: non-finite setting");
  }
  if (s.speed_kmh <= 0.0) throw std::invalid_argument("FullCarBumpRoad: speed_kmh must be > 0");
  if (s.ramp_up_length < 0.0 || s.flat_length < 0.0 || s.ramp_down_length < 0.0 ||
      s.right_offset < 0.0 || s.wheelbase < 0.0) {
    throw std::invalid_argument(
        "FullCarBumpRoad: lengths, right_offset and wheelbase must be >= 0");
  }
}

double FullCarBumpRoad::offset(int c) const {
  return (c % 2 == 1 ? s_.right_offset : 0.0) + (c >= 2 ? s_.wheelbase : 0.0);
}

void FullCarBumpRoad::heights(double t, Eigen::Ref<Eigen::VectorXd> out) const {
  const double travel = s_.speed_kmh / 3.6 * t;
  for (int c = 0; c < 4; ++c) {
    const double h = c % 2 == 0 ? s_.height_left : s_.height_right;
    out[c] = h * unitTrapezoid(travel - offset(c), s_.ramp_up_length, s_.flat_length,
                               s_.ramp_down_length);
  }
}

std::vector<double> FullCarBumpRoad::breakpoints(double t0, double t1) const {
  const double v = s_.speed_kmh / 3.6;
  std::vector<double> out;
  for (int c = 0; c < 4; ++c) {
    const double start = offset(c);
    const double at[4] = {start, start + s_.ramp_up_length,
                          start + s_.ramp_up_length + s_.flat_length,
                          start + s_.ramp_up_length + s_.flat_length + s_.ramp_down_length};
    for (double d : at) {
      const double t = d / v;
      if (t > t0 && t < t1) out.push_back(t);
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace pc_ekf
