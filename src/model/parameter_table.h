// A model's parameter table: the one place that names, orders, bounds and
// documents the values of a model. The parameter vector, the YAML reader, the
// per-entry part of invalidReason() and the doc tables (docs/models.md) all
// come from it, so no code keeps its own name-to-index list.
#pragma once

#include <Eigen/Dense>
#include <limits>
#include <string>
#include <vector>

namespace pc_ekf {

// Where a value is admissible. Lower bound open (> lower) unless
// zero_allowed (>= lower); upper bound closed, either the number `upper` or,
// when upper_sum is not empty, the sum of those parameters' values (e.g. a
// position along a bar bounded by its length).
struct ParameterDomain {
  double lower = 0.0;
  bool zero_allowed = false;
  double upper = std::numeric_limits<double>::infinity();
  std::vector<std::string> upper_sum;
  // A tighter lower bound (closed) for configured values only, NaN for none:
  // e.g. an added mass must be >= 0 in a config while the model still
  // accepts a slightly negative one at a collocation point.
  double config_lower = std::numeric_limits<double>::quiet_NaN();
};

struct ParameterSpec {
  std::string name;
  std::string unit;
  double default_value = 0.0;
  ParameterDomain domain;
  std::string description;  // one line
  // Not configured: this fraction of another entry's configured value (e.g.
  // an IMU midway between mounts whose spacing the user sets); "" = none.
  std::string default_fraction_of{};
  double default_fraction = 0.0;
};

// > 0, >= 0, any real, [0, sum of `parameters`].
inline ParameterDomain positive() { return ParameterDomain(); }
inline ParameterDomain nonNegative() {
  ParameterDomain d;
  d.zero_allowed = true;
  return d;
}
inline ParameterDomain anyValue() {
  ParameterDomain d;
  d.lower = -std::numeric_limits<double>::infinity();
  return d;
}
inline ParameterDomain withinSumOf(std::vector<std::string> parameters) {
  ParameterDomain d = nonNegative();
  d.upper_sum = std::move(parameters);
  return d;
}

class ParameterTable {
 public:
  ParameterTable() = default;
  // Throws std::invalid_argument for a duplicate or empty name, an unknown
  // upper_sum name or a default outside its domain.
  explicit ParameterTable(std::vector<ParameterSpec> specs);

  int size() const { return static_cast<int>(specs_.size()); }
  const ParameterSpec& operator[](int i) const { return specs_[static_cast<std::size_t>(i)]; }
  const std::vector<ParameterSpec>& specs() const { return specs_; }
  const std::vector<std::string>& names() const { return names_; }
  Eigen::VectorXd defaults() const;
  int index(const std::string& name) const;  // -1 when unknown
  int at(const std::string& name) const;     // std::invalid_argument when unknown

  // Upper bound of entry i for the vector `values` (upper_sum resolved).
  double upperBound(int i, const Eigen::Ref<const Eigen::VectorXd>& values) const;
  // "" or the first violation: the count, then a non-finite value, then the
  // open lower bounds, the closed ones and the upper bounds, each in table
  // order ("bar_mass = 0 must be > 0", "x = 2.7 outside [0, 2.6]").
  std::string violation(const Eigen::Ref<const Eigen::VectorXd>& values) const;
  // violation().empty() for a vector of size() values, with no branch per
  // entry (it runs for every collocation point of every forecast).
  bool admissible(const double* values) const;

  // "> 0", ">= 0", "[0, bar_length]", "any" (docs and messages).
  std::string domainText(int i) const;
  // A Markdown table: name | unit | default | domain | description.
  std::string markdown() const;

 private:
  std::vector<ParameterSpec> specs_;
  std::vector<std::string> names_;
  std::vector<std::vector<int>> upper_sum_;  // resolved indices
  // admissible()'s view of the domains: contiguous bounds (upper = +inf where
  // a sum bounds the entry) and the entries bounded by a sum.
  std::vector<double> lower_, upper_, zero_allowed_;  // zero_allowed_: 1 or 0
  std::vector<int> summed_;
};

}  // namespace pc_ekf
