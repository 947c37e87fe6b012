// The interface every mechanical system implements so that the filters never
// depend on a particular model (docs/method.md §2.6). All evaluation is batched over
// the collocation points: states and parameters are columns.
#pragma once

#include <Eigen/Dense>
#include <memory>
#include <string>
#include <vector>

#include "pc_ekf/model/model_description.h"

namespace pc_ekf {

class ContactRoad;

// A model evaluated for a fixed batch of parameter vectors (one column each).
// Built by MechanicalModel::prepare, which does the per-parameter work once
// (e.g. the static equilibrium), so derivatives() is cheap.
class ModelBatch {
 public:
  virtual ~ModelBatch() = default;
  virtual int pointCount() const = 0;
  // y and dydt: stateSize() x pointCount().
  virtual void derivatives(double t, const Eigen::ArrayXXd& y, Eigen::ArrayXXd& dydt) const = 0;
  // Initial state of every point at t = 0 (stateSize() x pointCount()).
  virtual Eigen::ArrayXXd initialState() const = 0;

  // Optional structure-of-arrays form, used by integrate() when
  // hasTransposedDerivatives(): y_t and dydt_t are pointCount() x stateSize()
  // (one contiguous column per state variable), so a model can vectorise its
  // right-hand side across the points. Values must equal those of
  // derivatives() up to rounding and must not depend on the other points of
  // the batch. The default transposes and calls derivatives().
  virtual bool hasTransposedDerivatives() const { return false; }
  virtual void derivativesTransposed(double t, const Eigen::ArrayXXd& y_t,
                                     Eigen::ArrayXXd& dydt_t) const;
};

class MechanicalModel {
 public:
  virtual ~MechanicalModel() = default;

  // Names, tables, channels and contacts: the model's one description (the
  // same object its ModelType returns).
  virtual const ModelDescription& description() const = 0;

  int stateSize() const { return static_cast<int>(description().stateNames().size()); }
  const std::vector<std::string>& stateNames() const { return description().stateNames(); }

  // Full parameter vector (every physical constant of the model), in the
  // order of description().parameters().
  const std::vector<std::string>& parameterNames() const {
    return description().parameters().names();
  }
  virtual const Eigen::VectorXd& nominalParameters() const = 0;
  // "" when the parameter vector is physically admissible, else why not
  // (e.g. "added_mass_position = 1.7 outside [0, 1.524]"). Default: the
  // parameter table's domains; a model with rules across entries adds them.
  virtual std::string invalidReason(const Eigen::Ref<const Eigen::VectorXd>& params) const {
    return description().parameters().violation(params);
  }

  // Measurement channels and the linear observation z = H y (channels x states).
  const std::vector<std::string>& channelNames() const { return description().channelNames(); }
  virtual const Eigen::MatrixXd& observationMatrix() const = 0;

  // params: parameterNames().size() x Q. Columns must be admissible.
  virtual std::unique_ptr<ModelBatch> prepare(const Eigen::MatrixXd& params) const = 0;

  // Kinks of the model's inputs in (t0, t1) (see RoadInput::breakpoints).
  virtual std::vector<double> breakpoints(double t0, double t1) const = 0;

  // The road the model rides on (nullptr for a model without one), so that a
  // variant of the model (another vehicle) can be built on the same road.
  virtual const ContactRoad* contactRoad() const { return nullptr; }

  int parameterIndex(const std::string& name) const;  // -1 when unknown
};

}  // namespace pc_ekf
