// The binding of a built-in model's table entries to its fields, shared by
// the roll plane's and the full car's descriptions. A model declares its
// fields once, as a struct template over the element type: Fields<double>
// holds values (its typed copy, e.g. VehicleParameters), Fields<int> each
// field's row in its table, so that prepare() reads a point's values by row
// from its column of the parameter matrix, with no name lookup and no copy.
#pragma once

#include <Eigen/Dense>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "pc_ekf/model/model_description.h"
#include "pc_ekf/model/parameter_table.h"
#include "pc_ekf/model/suspension_laws.h"

namespace pc_ekf {

template <template <class> class Fields>
struct FieldEntry {
  ParameterSpec spec;
  double& (*value)(Fields<double>&);
  int& (*row)(Fields<int>&);
  // access: PC_EKF_FIELD(member), one accessor for both element types.
  template <class Access>
  FieldEntry(ParameterSpec s, Access access) : spec(std::move(s)), value(access), row(access) {}
};
#define PC_EKF_FIELD(member) [](auto& f) -> auto& { return f.member; }

// One table of a model (its parameters, or its settings), entries in order.
template <template <class> class Fields>
class FieldTable {
 public:
  explicit FieldTable(std::vector<FieldEntry<Fields>> entries) : entries_(std::move(entries)) {}
  ParameterTable table() const {
    std::vector<ParameterSpec> specs;
    for (const auto& e : entries_) specs.push_back(e.spec);
    return ParameterTable(std::move(specs));
  }
  // Sets each of this table's fields in `rows` to its row (entry index).
  void rowsInto(Fields<int>& rows) const {
    for (std::size_t i = 0; i < entries_.size(); ++i) entries_[i].row(rows) = static_cast<int>(i);
  }
  Eigen::VectorXd read(Fields<double> f) const {
    Eigen::VectorXd v(static_cast<Eigen::Index>(entries_.size()));
    for (std::size_t i = 0; i < entries_.size(); ++i) {
      v[static_cast<Eigen::Index>(i)] = entries_[i].value(f);
    }
    return v;
  }
  void write(const Eigen::Ref<const Eigen::VectorXd>& v, Fields<double>& f) const {
    for (std::size_t i = 0; i < entries_.size(); ++i) {
      entries_[i].value(f) = v[static_cast<Eigen::Index>(i)];
    }
  }

 private:
  std::vector<FieldEntry<Fields>> entries_;
};

// A built-in's parameter and setting tables, every field's row, and the
// conversions of its typed copy (Typed: Fields<double> and a `damper` law,
// the model's one choice) to and from ModelParameters.
template <template <class> class Fields>
class ModelFields {
 public:
  ModelFields(FieldTable<Fields> parameters, FieldTable<Fields> settings)
      : parameters_(std::move(parameters)), settings_(std::move(settings)) {
    parameters_.rowsInto(rows_);
    settings_.rowsInto(rows_);
  }
  const FieldTable<Fields>& parameters() const { return parameters_; }
  const FieldTable<Fields>& settings() const { return settings_; }
  // A parameter's row in the parameter vector, a setting's in the settings.
  const Fields<int>& rows() const { return rows_; }

  // The description's defaults into p's fields.
  template <class Typed>
  void setDefaults(const ModelDescription& d, Typed& p) const {
    parameters_.write(d.parameters().defaults(), p);
    settings_.write(d.settings().defaults(), p);
  }
  // v's values into a copy of `laws` (its settings and damper law are kept);
  // std::invalid_argument, prefixed by `who`, for a vector of another size.
  template <class Typed>
  Typed fromVector(const ModelDescription& d, const Eigen::Ref<const Eigen::VectorXd>& v,
                   const Typed& laws, const std::string& who) const {
    const int n = d.parameters().size();
    if (v.size() != n) {
      throw std::invalid_argument(who + ": expected " + std::to_string(n) + " values, got " +
                                  std::to_string(v.size()));
    }
    Typed p = laws;
    parameters_.write(v, p);
    return p;
  }
  template <class Typed>
  Typed from(const ModelDescription& d, const ModelParameters& m, const std::string& who) const {
    Typed p = fromVector(d, m.values, Typed(), who);
    settings_.write(m.settings, p);
    p.damper = damperLaw(m.choice(d, "damper"));
    return p;
  }
  template <class Typed>
  ModelParameters toModelParameters(const Typed& p) const {
    ModelParameters m;
    m.values = parameters_.read(p);
    m.settings = settings_.read(p);
    m.choices = {damperChoiceName(p.damper)};
    return m;
  }

 private:
  FieldTable<Fields> parameters_, settings_;
  Fields<int> rows_{};
};

}  // namespace pc_ekf
