#include "pc_ekf/model/reading_inputs.h"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <stdexcept>

namespace pc_ekf {

ReadingInputs::ReadingInputs(std::vector<std::string> names, std::vector<double> times,
                             std::vector<std::vector<double>> columns)
    : names_(std::move(names)),
      t_(std::move(times)),
      v_(std::move(columns)),
      series_(static_cast<int>(std::max<std::size_t>(v_.size(), 1))) {
  if (t_.empty()) throw std::invalid_argument("road-free inputs: no samples");
  if (v_.size() != names_.size()) throw std::invalid_argument("road-free inputs: column count");
  for (std::size_t k = 1; k < t_.size(); ++k) {
    if (!(t_[k] > t_[k - 1])) throw std::invalid_argument("road-free inputs: times must increase");
  }
  for (std::size_t c = 0; c < v_.size(); ++c) {
    std::vector<double>& col = v_[c];
    if (col.size() != t_.size()) throw std::invalid_argument("road-free inputs: column length");
    // Fill gaps linearly between read samples, held at the ends.
    std::vector<std::size_t> read;
    for (std::size_t k = 0; k < col.size(); ++k) {
      if (std::isfinite(col[k])) read.push_back(k);
    }
    if (read.empty()) {
      throw std::invalid_argument("road-free estimation needs the reading '" + names_[c] +
                                  "' as an input, and the record has none");
    }
    for (std::size_t k = 0; k < col.size(); ++k) {
      if (std::isfinite(col[k])) continue;
      const auto next = std::upper_bound(read.begin(), read.end(), k);
      if (next == read.begin()) {
        col[k] = col[read.front()];
      } else if (next == read.end()) {
        col[k] = col[read.back()];
      } else {
        const std::size_t a = *(next - 1), b = *next;
        col[k] = col[a] + (col[b] - col[a]) * (t_[k] - t_[a]) / (t_[b] - t_[a]);
      }
    }
    std::vector<double> cum(col.size());
    cum[0] = col[0] * t_[0];  // the first value from t = 0
    for (std::size_t k = 1; k < col.size(); ++k) {
      cum[k] = cum[k - 1] + 0.5 * (col[k] + col[k - 1]) * (t_[k] - t_[k - 1]);
    }
    cum_.push_back(std::move(cum));
  }
  series_ = SampledRoad(t_, v_);
}

ReadingInputs::ReadingInputs(std::vector<std::string> names)
    : names_(std::move(names)),
      v_(names_.size()),
      cum_(names_.size()),
      series_(static_cast<int>(std::max<std::size_t>(names_.size(), 1))) {}

std::string ReadingInputs::append(double t, const double* values) {
  if (!std::isfinite(t) || (!t_.empty() && !(t > t_.back()))) {
    return "road-free inputs: sample time " + std::to_string(t) + " not after the last one";
  }
  std::vector<double> row(names_.size());
  for (std::size_t c = 0; c < names_.size(); ++c) {
    row[c] = values[c];
    if (std::isnan(row[c]) && !t_.empty()) row[c] = v_[c].back();
    if (!std::isfinite(row[c])) {
      return "road-free input '" + names_[c] + "' " +
             (std::isnan(values[c]) ? "not read yet" : "not finite");
    }
  }
  std::unique_lock<std::shared_mutex> lock(mutex_);
  series_.append(t, names_.empty() ? std::vector<double>{0.0} : row);
  for (std::size_t c = 0; c < names_.size(); ++c) {
    // The first value from t = 0, as the whole record's.
    cum_[c].push_back(t_.empty() ? row[c] * t
                                 : cum_[c].back() + 0.5 * (row[c] + v_[c].back()) * (t - t_.back()));
    v_[c].push_back(row[c]);
  }
  t_.push_back(t);
  return "";
}

void ReadingInputs::at(double t, double* out) const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  Eigen::Map<Eigen::VectorXd> values(out, count());
  series_.heights(t, values);
}

double ReadingInputs::previousTime(double t) const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  const auto it = std::lower_bound(t_.begin(), t_.end(), t);
  return it == t_.begin() ? 0.0 : *(it - 1);
}

double ReadingInputs::integral(int c, double t) const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  const std::vector<double>& col = v_[static_cast<std::size_t>(c)];
  const std::vector<double>& cum = cum_[static_cast<std::size_t>(c)];
  if (t <= t_.front()) return col[0] * std::max(t, 0.0);
  if (t >= t_.back()) return cum.back() + col.back() * (t - t_.back());
  const std::size_t i = std::upper_bound(t_.begin(), t_.end(), t) - t_.begin() - 1;
  double value[1];
  // The interpolated value at t, then the trapezoid from t_i to t.
  const double w = (t - t_[i]) / (t_[i + 1] - t_[i]);
  value[0] = col[i] + w * (col[i + 1] - col[i]);
  return cum[i] + 0.5 * (col[i] + value[0]) * (t - t_[i]);
}

double ReadingInputs::mean(int c) const {
  const std::vector<double>& col = v_[static_cast<std::size_t>(c)];
  double s = 0.0;
  for (double v : col) s += v;
  return s / static_cast<double>(col.size());
}

double ReadingInputs::rms(int c) const {
  const std::vector<double>& col = v_[static_cast<std::size_t>(c)];
  double s = 0.0;
  for (double v : col) s += v * v;
  return std::sqrt(s / static_cast<double>(col.size()));
}

void ReadingInputs::setNoiseCorrelation(int c, double rho) {
  if (c < 0 || c >= count() || !(rho > -1.0 && rho < 1.0)) {
    throw std::invalid_argument("ReadingInputs::setNoiseCorrelation: input " + std::to_string(c) +
                                ", correlation " + std::to_string(rho) + " outside (-1, 1)");
  }
  rho_.resize(names_.size(), 0.0);
  rho_[static_cast<std::size_t>(c)] = rho;
}

double ReadingInputs::noiseCorrelation(int c) const {
  return static_cast<std::size_t>(c) < rho_.size() ? rho_[static_cast<std::size_t>(c)] : 0.0;
}

}  // namespace pc_ekf
