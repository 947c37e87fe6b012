#include "pc_ekf/model/parameter_table.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "pc_ekf/model/domain_message.h"

namespace pc_ekf {

namespace {

bool hasUpper(const ParameterSpec& s) {
  return !s.domain.upper_sum.empty() || std::isfinite(s.domain.upper);
}

}  // namespace

ParameterTable::ParameterTable(std::vector<ParameterSpec> specs) : specs_(std::move(specs)) {
  for (const auto& s : specs_) {
    if (s.name.empty()) throw std::invalid_argument("ParameterTable: an entry without a name");
    if (index(s.name) >= 0) throw std::invalid_argument("ParameterTable: '" + s.name + "' twice");
    names_.push_back(s.name);
  }
  for (const auto& s : specs_) {
    std::vector<int> sum;
    for (const auto& n : s.domain.upper_sum) sum.push_back(at(n));
    upper_sum_.push_back(std::move(sum));
    lower_.push_back(s.domain.lower);
    upper_.push_back(s.domain.upper_sum.empty() ? s.domain.upper
                                                : std::numeric_limits<double>::infinity());
    zero_allowed_.push_back(s.domain.zero_allowed ? 1.0 : 0.0);
    if (!s.domain.upper_sum.empty()) summed_.push_back(static_cast<int>(upper_.size()) - 1);
  }
  const std::string why = violation(defaults());
  if (!why.empty()) throw std::invalid_argument("ParameterTable: default " + why);
}

Eigen::VectorXd ParameterTable::defaults() const {
  Eigen::VectorXd v(size());
  for (int i = 0; i < size(); ++i) v[i] = specs_[i].default_value;
  return v;
}

int ParameterTable::index(const std::string& name) const {
  for (std::size_t i = 0; i < names_.size(); ++i) {
    if (names_[i] == name) return static_cast<int>(i);
  }
  return -1;
}

int ParameterTable::at(const std::string& name) const {
  const int i = index(name);
  if (i < 0) throw std::invalid_argument("ParameterTable: no parameter '" + name + "'");
  return i;
}

double ParameterTable::upperBound(int i, const Eigen::Ref<const Eigen::VectorXd>& values) const {
  const auto& sum = upper_sum_[static_cast<std::size_t>(i)];
  if (sum.empty()) return specs_[i].domain.upper;
  double u = 0.0;
  for (int j : sum) u += values[j];
  return u;
}

std::string ParameterTable::violation(const Eigen::Ref<const Eigen::VectorXd>& values) const {
  if (values.size() != size()) {
    return "expected " + std::to_string(size()) + " parameters, got " +
           std::to_string(values.size());
  }
  for (int i = 0; i < size(); ++i) {
    if (!std::isfinite(values[i])) return outOfDomain(names_[i], values[i], "is not finite");
  }
  // Open lower bounds, then closed ones, then the ranges (ascending checks
  // give the same first violation as the models' earlier hand-written rules).
  for (const bool closed : {false, true}) {
    for (int i = 0; i < size(); ++i) {
      const ParameterDomain& d = specs_[i].domain;
      if (d.zero_allowed != closed || hasUpper(specs_[i])) continue;
      if (closed ? values[i] < d.lower : values[i] <= d.lower) {
        return outOfDomain(names_[i], values[i], "must be " + domainText(i));
      }
    }
  }
  for (int i = 0; i < size(); ++i) {
    if (!hasUpper(specs_[i])) continue;
    const ParameterDomain& d = specs_[i].domain;
    const double up = upperBound(i, values), v = values[i];
    if ((d.zero_allowed ? v < d.lower : v <= d.lower) || v > up) {
      return outOfDomain(names_[i], v,
                         std::string("outside ") + (d.zero_allowed ? "[" : "(") +
                             domainNumber(d.lower) + ", " + domainNumber(up) + "]");
    }
  }
  return "";
}

namespace {

// 1 when every value is finite and inside its bounds: lower open (v > lower)
// or closed where zero_ok is 1, upper closed. Integer masks and no early exit,
// so that the loop vectorises.
#if defined(__x86_64__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
int withinBounds(const double* v, const double* lower, const double* upper,
                 const double* zero_ok, int count) {
  int ok = 1;
  for (int i = 0; i < count; ++i) {
    const double x = v[i];
    const int above = (x > lower[i]) | ((zero_ok[i] != 0.0) & (x == lower[i]));
    ok &= above & (x <= upper[i]) & ((x - x) == 0.0);  // x - x: NaN for NaN or +-Inf
  }
  return ok;
}

}  // namespace

bool ParameterTable::admissible(const double* values) const {
  bool ok = withinBounds(values, lower_.data(), upper_.data(), zero_allowed_.data(), size()) != 0;
  for (int i : summed_) {
    double up = 0.0;
    for (int j : upper_sum_[static_cast<std::size_t>(i)]) up += values[j];
    ok &= values[i] <= up;
  }
  return ok;
}

std::string ParameterTable::domainText(int i) const {
  const ParameterSpec& s = specs_[i];
  const ParameterDomain& d = s.domain;
  std::string up;
  if (!d.upper_sum.empty()) {
    for (const auto& n : d.upper_sum) up += (up.empty() ? "" : " + ") + n;
  } else if (std::isfinite(d.upper)) {
    up = domainNumber(d.upper);
  }
  const std::string lo = domainNumber(d.lower);
  if (!up.empty()) {
    return std::string(d.zero_allowed ? "[" : "(") + (std::isfinite(d.lower) ? lo : "-inf") + ", " +
           up + "]";
  }
  if (!std::isfinite(d.lower)) return "any";
  return std::string(d.zero_allowed ? ">= " : "> ") + lo;
}

std::string ParameterTable::markdown() const {
  std::ostringstream o;
  o << "| name | unit | default | domain | description |\n|---|---|---|---|---|\n";
  for (int i = 0; i < size(); ++i) {
    const ParameterSpec& s = specs_[i];
    std::string domain = domainText(i);
    if (!std::isnan(s.domain.config_lower)) {
      domain += " (configured: >= " + domainNumber(s.domain.config_lower) + ")";
    }
    o << "| `" << s.name << "` | " << (s.unit.empty() ? "-" : s.unit) << " | "
      << domainNumber(s.default_value) << " | " << domain << " | " << s.description << " |\n";
  }
  return o.str();
}

}  // namespace pc_ekf
