// y' = a y (the paper's appendix system), batched over parameter columns [a, y0].
#include "pc_ekf/model/scalar_growth_model.h"

#include <cmath>
#include <stdexcept>

namespace pc_ekf {

namespace {

class ScalarGrowthBatch : public ModelBatch {
 public:
  explicit ScalarGrowthBatch(const Eigen::MatrixXd& params)
      : rate_(params.row(0).transpose().array()), initial_(params.row(1).array()) {}

  int pointCount() const override { return static_cast<int>(rate_.size()); }

  void derivatives(double, const Eigen::ArrayXXd& y, Eigen::ArrayXXd& dydt) const override {
    if (y.rows() != 1 || y.cols() != pointCount()) {
      throw std::invalid_argument("ScalarGrowthModel: state batch must be 1 x pointCount()");
    }
    dydt.resize(1, y.cols());
    dydt.row(0) = y.row(0) * rate_.transpose();
  }

  Eigen::ArrayXXd initialState() const override { return initial_; }

 private:
  Eigen::ArrayXd rate_;
  Eigen::ArrayXXd initial_;  // 1 x Q
};

}  // namespace

ScalarGrowthModel::ScalarGrowthModel(double a, double y0)
    : nominal_(Eigen::Vector2d(a, y0)), h_(Eigen::MatrixXd::Ones(1, 1)) {}

const ModelDescription& ScalarGrowthModel::description() const {
  static const ModelDescription d({"scalar_growth",
                                   "y' = a y, y(0) = y0 (a test model)",
                                   ParameterTable({{"growth_rate", "1/s", 1.0, anyValue(), "a"},
                                                   {"initial_value", "", 1.0, anyValue(), "y0"}}),
                                   {},
                                   {},
                                   {"y"},
                                   {{"y", "", "the state"}},
                                   {},
                                   {}});
  return d;
}

std::unique_ptr<ModelBatch> ScalarGrowthModel::prepare(const Eigen::MatrixXd& params) const {
  if (params.rows() != 2)
    throw std::invalid_argument("ScalarGrowthModel::prepare: expected 2 rows");
  return std::make_unique<ScalarGrowthBatch>(params);
}

}  // namespace pc_ekf
