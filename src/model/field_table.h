// The binding of a built-in model's table entries to its fields, shared by
// the roll plane's and the full car's descriptions. A model declares its
// fields once, as a struct template over the element type: Fields<double>
// holds values (its typed copy, e.g. VehicleParameters), Fields<int> each
// field's row in its table, so that prepare() reads a point's values by row
// from its column of the parameter matrix, with no name lookup and no copy.
#pragma once

#include <Eigen/Dense>
#include <utility>
#include <vector>

#include "pc_ekf/model/parameter_table.h"

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

}  // namespace pc_ekf
