// The uncertain parameters theta of the extended state [y; theta] and their
// map into the model's full parameter vector (docs/method.md §1.1, §4).
#pragma once

#include <Eigen/Dense>
#include <string>
#include <vector>

#include "pc_ekf/model/mechanical_model.h"
#include "pc_ekf/pc/germ.h"
#include "pc_ekf/pc/polynomial_basis.h"

namespace pc_ekf {

// value = nominal * (1 + relative_range * xi), xi the germ (docs/method.md §1.1).
struct UncertainParameter {
  std::string name;  // one of the model's parameter names
  double nominal = 0.0;
  double relative_range = 0.0;
  GermSpec germ;
};

class ParameterMapping {
 public:
  // Throws std::invalid_argument when a name is not a model parameter.
  ParameterMapping(const MechanicalModel& model, std::vector<UncertainParameter> uncertain);

  int count() const { return static_cast<int>(uncertain_.size()); }
  const std::vector<UncertainParameter>& uncertain() const { return uncertain_; }
  std::vector<GermSpec> germs() const;
  std::vector<std::string> names() const;
  // The model's full parameter vector: its names and nominal (configured) values.
  const std::vector<std::string>& modelParameterNames() const { return model_names_; }
  const Eigen::VectorXd& nominalParameters() const { return nominal_full_; }

  // theta (count x Q) -> full model parameters (model parameters x Q), the
  // others at their nominal values.
  Eigen::MatrixXd fullParameters(const Eigen::MatrixXd& theta) const;
  // The same into columns [begin, end) of `full` (model parameters x Q, sized
  // by the caller) from those columns of theta: the forecast fills its own
  // buffer, a part per thread, with no allocation.
  void fillFullParameters(const Eigen::Ref<const Eigen::MatrixXd>& theta, Eigen::Index begin,
                          Eigen::Index end, Eigen::MatrixXd& full) const;
  // Parameter values at germ points (rows of xi, Q x count) -> count x Q.
  Eigen::MatrixXd valuesAtGerms(const Eigen::MatrixXd& xi) const;
  // Germ coordinates of parameter values (inverse of the affine map).
  Eigen::VectorXd germOf(const Eigen::VectorXd& values) const;
  // Prior coefficients (count x S): exact, the map is affine in each germ.
  Eigen::MatrixXd priorCoefficients(const PolynomialBasis& basis) const;
  // Coefficients (count x S) of an affine distribution in the same germs with
  // the given means and standard deviations (a working prior for
  // re-linearisation, docs/method.md §4.9). A std is shrunk where its support
  // would leave the prior's; a row is zero when its mean is not strictly inside.
  // recentre: instead, the mean moves inwards until the asked std fits (the
  // std shrinks only where the prior's support is narrower than the working
  // one): with the prior put back, the working prior's centre is free.
  Eigen::MatrixXd workingCoefficients(const PolynomialBasis& basis, const Eigen::VectorXd& mean,
                                      const Eigen::VectorXd& stddev, bool recentre = false) const;
  // Support of each parameter under its prior germ (may be infinite).
  double lowerBound(int i) const;
  double upperBound(int i) const;

 private:
  Eigen::VectorXd nominal_full_;
  std::vector<std::string> model_names_;
  std::vector<int> index_;  // row of each uncertain parameter in the full vector
  std::vector<UncertainParameter> uncertain_;
};

}  // namespace pc_ekf
