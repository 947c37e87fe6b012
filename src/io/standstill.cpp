#include "pc_ekf/io/standstill.h"

#include <cmath>
#include <stdexcept>

namespace pc_ekf {

namespace {
constexpr double kEnter = 1.5;  // std: a window's RMS / spread below this is noise
constexpr double kLeave = 5.0;  // std: a reading beyond this is motion
constexpr double kStep = 3.0;   // std of the difference of a window's halves' means
}  // namespace

Standstill::Standstill(double window, std::vector<int> travels, std::vector<int> rates,
                       std::vector<double> absolute, std::vector<double> relative)
    : window_(window),
      travels_(std::move(travels)),
      rates_(std::move(rates)),
      absolute_(std::move(absolute)),
      relative_(std::move(relative)),
      sums_(absolute_.size(), 0.0) {
  if (relative_.size() != absolute_.size()) throw std::invalid_argument("Standstill: noise sizes");
}

double Standstill::sigma(int input, double reading) const {
  const auto i = static_cast<std::size_t>(input);
  return std::hypot(absolute_[i], relative_[i] * reading);
}

Standstill::Decision Standstill::decide(double t, const std::vector<double>& in) const {
  Decision d;
  if (!enabled() || (travels_.empty() && rates_.empty())) return d;
  for (int i : travels_) {
    if (!std::isfinite(in[static_cast<std::size_t>(i)])) return d;
  }
  for (int i : rates_) {
    if (!std::isfinite(in[static_cast<std::size_t>(i)])) return d;
  }
  if (standing_) {
    const double n = static_cast<double>(count_);
    for (int i : rates_) {
      const double v = in[static_cast<std::size_t>(i)];
      if (std::abs(v) > kLeave * sigma(i, 0.0)) return d;
    }
    // A reading far off, or the last window's mean off the stop's (a
    // small load put in settles the body by less than a reading's noise).
    const std::size_t rows = times_.size();
    for (int i : travels_) {
      const auto c = static_cast<std::size_t>(i);
      const double u = in[c];
      const double mean = sums_[c] / n;
      if (std::abs(u - mean) > kLeave * sigma(i, mean)) return d;
      double recent = u;
      for (std::size_t r = 0; r < rows; ++r) recent += value(r, c);
      recent /= static_cast<double>(rows + 1);
      if (std::abs(recent - mean) > kLeave * sigma(i, mean) / std::sqrt(static_cast<double>(rows + 1))) {
        return d;
      }
    }
    d.standing = true;
    d.averaged = count_ + 1;
    return d;
  }
  // Entering: the window, this sample included, must span `window` s.
  if (times_.empty() || t - times_.front() < window_ * (1.0 - 1e-9)) return d;
  const std::size_t rows = times_.size();
  const double n = static_cast<double>(rows + 1);
  for (int i : rates_) {
    const auto c = static_cast<std::size_t>(i);
    double square = in[c] * in[c];
    for (std::size_t r = 0; r < rows; ++r) square += value(r, c) * value(r, c);
    const double s = sigma(i, 0.0);
    if (!(square / n <= kEnter * kEnter * s * s)) return d;
  }
  for (int i : travels_) {
    const auto c = static_cast<std::size_t>(i);
    double sum = in[c], square = in[c] * in[c];
    for (std::size_t r = 0; r < rows; ++r) {
      sum += value(r, c);
      square += value(r, c) * value(r, c);
    }
    const double mean = sum / n;
    const double s = sigma(i, mean);
    if (!(square / n - mean * mean <= kEnter * kEnter * s * s)) return d;
    // No step inside the window (a load just put in): its halves' means
    // agree within 3 std of their difference, 2 s / sqrt(n).
    double first = 0.0;
    const std::size_t half = (rows + 1) / 2;
    for (std::size_t r = 0; r < half; ++r) first += value(r, c);
    const double second = sum - first;
    const double step = second / (n - static_cast<double>(half)) - first / static_cast<double>(half);
    if (!(std::abs(step) <= kStep * 2.0 * s / std::sqrt(n))) return d;
  }
  d.standing = true;
  d.averaged = static_cast<long>(rows) + 1;
  return d;
}

void Standstill::apply(const Decision& d, const std::vector<double>& raw,
                       std::vector<double>* in) const {
  if (!d.standing) return;
  for (int i : rates_) (*in)[static_cast<std::size_t>(i)] = 0.0;
  for (int i : travels_) {
    const auto c = static_cast<std::size_t>(i);
    double sum = 0.0;
    if (standing_) {
      sum = sums_[c] + raw[c];
    } else {  // a stop just recognised: the window's readings
      sum = raw[c];
      for (std::size_t r = 0; r < times_.size(); ++r) sum += value(r, c);
    }
    (*in)[c] = sum / static_cast<double>(d.averaged);
  }
}

void Standstill::commit(double t, const std::vector<double>& raw, const Decision& d) {
  if (!enabled()) return;
  if (d.standing) {
    for (int i : travels_) {
      const auto c = static_cast<std::size_t>(i);
      if (!standing_) {
        sums_[c] = 0.0;
        for (std::size_t r = 0; r < times_.size(); ++r) sums_[c] += value(r, c);
      }
      sums_[c] += raw[c];
    }
    if (!standing_) ++stops_;
    count_ = d.averaged;
    ++standing_samples_;
  } else {
    count_ = 0;
    // A stop just ended: recognising one again takes a whole window of
    // quiet readings after it (the window before still reads quiet while
    // the vehicle drives off).
    if (standing_) {
      times_.clear();
      values_.clear();
    }
  }
  standing_ = d.standing;
  times_.push_back(t);
  values_.insert(values_.end(), raw.begin(), raw.end());
  while (!times_.empty() && times_.front() < t - window_) {
    times_.pop_front();
    values_.erase(values_.begin(), values_.begin() + static_cast<std::ptrdiff_t>(raw.size()));
  }
}

}  // namespace pc_ekf
