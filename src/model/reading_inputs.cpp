#include "pc_ekf/model/reading_inputs.h"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <stdexcept>

namespace pc_ekf {

namespace {

// Samples are forgotten in chunks of at least this many (and of at least
// as many as stay after them): each is moved O(1) times on average.
constexpr std::size_t kForgetChunk = 4096;

}  // namespace

ReadingInputs::ReadingInputs(std::vector<std::string> names, std::vector<double> times,
                             std::vector<std::vector<double>> columns)
    : names_(std::move(names)), t_(std::move(times)), v_(std::move(columns)) {
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
  samples_ = t_.size();
}

ReadingInputs::ReadingInputs(std::vector<std::string> names)
    : names_(std::move(names)), v_(names_.size()), cum_(names_.size()) {}

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
  for (std::size_t c = 0; c < names_.size(); ++c) {
    // The first value from t = 0, as the whole record's.
    cum_[c].push_back(t_.empty() ? row[c] * t
                                 : cum_[c].back() + 0.5 * (row[c] + v_[c].back()) * (t - t_.back()));
    v_[c].push_back(row[c]);
  }
  t_.push_back(t);
  ++samples_;
  // In sample order, as a loop over the samples would add them.
  for (std::size_t s = 0; s < sums_.size(); ++s) sums_[s] += sum_terms_[s](row.data());
  return "";
}

std::size_t ReadingInputs::held() const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  return t_.size();
}

double ReadingInputs::time(std::size_t k) const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  if (k >= samples_ || (k >= prefix_ && k < prefix_ + skipped_)) {
    throw std::out_of_range("road-free inputs: sample " + std::to_string(k) +
                            (k >= samples_ ? " not appended yet" : " forgotten"));
  }
  return t_[k < prefix_ || skipped_ == 0 ? k : k - skipped_];
}

void ReadingInputs::forgotten(const char* what, double t) const {
  throw std::logic_error(std::string("road-free inputs: ") + what + " at t = " + std::to_string(t) +
                         " s needs samples already forgotten");
}

void ReadingInputs::at(double t, double* out) const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  const std::size_t n = names_.size();
  if (t_.empty()) {
    std::fill(out, out + n, 0.0);  // no input yet: at rest
    return;
  }
  if (t <= t_.front() || t >= t_.back()) {
    if (t < t_.front() && frontForgotten()) forgotten("an input", t);
    const std::size_t k = t <= t_.front() ? 0 : t_.size() - 1;
    for (std::size_t c = 0; c < n; ++c) out[c] = v_[c][k];
    return;
  }
  const std::size_t i = std::upper_bound(t_.begin(), t_.end(), t) - t_.begin() - 1;
  if (inGap(i, t)) forgotten("an input", t);
  const double w = (t - t_[i]) / (t_[i + 1] - t_[i]);
  for (std::size_t c = 0; c < n; ++c) out[c] = v_[c][i] + w * (v_[c][i + 1] - v_[c][i]);
}

double ReadingInputs::previousTime(double t) const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  const std::size_t q = std::lower_bound(t_.begin(), t_.end(), t) - t_.begin();
  // Just after the forgotten samples the previous one is among them.
  if (skipped_ > 0 && q == prefix_) forgotten("the previous sample", t);
  return q == 0 ? 0.0 : t_[q - 1];
}

double ReadingInputs::integral(int c, double t) const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  if (t_.empty()) return 0.0;
  const std::vector<double>& col = v_[static_cast<std::size_t>(c)];
  const std::vector<double>& cum = cum_[static_cast<std::size_t>(c)];
  if (t < t_.front() && frontForgotten()) forgotten("an integral", t);
  if (t <= t_.front() && !frontForgotten()) return col[0] * std::max(t, 0.0);
  if (t >= t_.back()) return cum.back() + col.back() * (t - t_.back());
  const std::size_t i = std::upper_bound(t_.begin(), t_.end(), t) - t_.begin() - 1;
  if (inGap(i, t)) forgotten("an integral", t);
  double value[1];
  // The interpolated value at t, then the trapezoid from t_i to t.
  const double w = (t - t_[i]) / (t_[i + 1] - t_[i]);
  value[0] = col[i] + w * (col[i + 1] - col[i]);
  return cum[i] + 0.5 * (col[i] + value[0]) * (t - t_[i]);
}

int ReadingInputs::addSampleSum(std::function<double(const double*)> f) const {
  std::unique_lock<std::shared_mutex> lock(mutex_);
  if (skipped_ > 0) {
    throw std::logic_error("road-free inputs: a sample sum after samples were forgotten");
  }
  double sum = 0.0;
  std::vector<double> row(names_.size());
  for (std::size_t k = 0; k < t_.size(); ++k) {
    for (std::size_t c = 0; c < row.size(); ++c) row[c] = v_[c][k];
    sum += f(row.data());
  }
  sum_terms_.push_back(std::move(f));
  sums_.push_back(sum);
  return static_cast<int>(sums_.size()) - 1;
}

double ReadingInputs::sampleSum(int handle) const {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  return sums_.at(static_cast<std::size_t>(handle));
}

void ReadingInputs::forget(double needed_from, double kept_until) {
  if (t_.size() <= 2) return;
  // The first stored sample to keep: the one before the sample at or before needed_from.
  const auto after = [this](double t) {
    return static_cast<std::size_t>(std::upper_bound(t_.begin(), t_.end(), t) - t_.begin());
  };
  const std::size_t at_or_before = std::max<std::size_t>(after(needed_from), 1) - 1;
  const std::size_t from = std::min(at_or_before > 0 ? at_or_before - 1 : 0, t_.size() - 2);
  // The record's first samples that stay: once some were forgotten, those
  // already kept (a gap cannot be filled again).
  const std::size_t first = skipped_ > 0 ? prefix_ : after(kept_until);
  if (from <= first || from - first < std::max(kForgetChunk, t_.size() - from)) return;
  std::unique_lock<std::shared_mutex> lock(mutex_);
  const auto drop = [first, from](std::vector<double>& v) {
    v.erase(v.begin() + static_cast<std::ptrdiff_t>(first),
            v.begin() + static_cast<std::ptrdiff_t>(from));
  };
  drop(t_);
  for (auto& col : v_) drop(col);
  for (auto& col : cum_) drop(col);
  prefix_ = first;
  skipped_ += from - first;
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
