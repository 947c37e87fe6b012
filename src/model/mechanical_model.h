// The interface every mechanical system implements so that the filters never
// depend on a particular model (docs/method.md §2.6). All evaluation is batched over
// the collocation points: states and parameters are columns.
#pragma once

#include <Eigen/Dense>
#include <functional>
#include <limits>
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

  // Readings kept as states (MechanicalModel::readingCount() > 0): fills the
  // last readingCount() rows of y (stateSize() x pointCount()) with every
  // channel's reading at t, from the dynamic rows above them. integrate()
  // calls it at the end of every interval; initialState() includes them.
  virtual void readings(double /*t*/, Eigen::ArrayXXd& /*y*/) const {}
  // Readings stamped t by a sensor whose clock runs `shift` ahead of the
  // inputs': what the inputs drive is taken at t - shift, what the sensor
  // carries itself (a road-free IMU's gyro and its integral) at t. Models
  // whose inputs are not read (shift 0 only) keep the default.
  virtual void readingsShifted(double t, double shift, Eigen::ArrayXXd& y) const {
    readings(t - shift, y);
  }
  // Road-free models whose roll is the gyro's integral: point q's later
  // readings take the roll as that plus roll[q] (rad: a tilt the gyro never
  // saw, less a gyro bias's drift) and the lateral acceleration a_y plus
  // lateral[q] (m/s^2: a road's cross-fall beta gives g sin(beta)); one
  // entry per point. False: not supported.
  virtual bool offsetPoints(const Eigen::VectorXd& /*roll*/, const Eigen::VectorXd& /*lateral*/) {
    return false;
  }
};

// How readings are zeroed (measurement.zero), docs/method.md §1.6:
//  kRest: every channel is a deviation from its value with the loaded vehicle
//         at rest (the paper's convention);
//  kTare: as the sensors give them: suspension travel from the empty vehicle
//         at rest on level ground (the load's static sag is in the reading),
//         the accelerometer raw (+g along z at rest, REP 145).
enum class ZeroConvention { kRest, kTare };
std::string toString(ZeroConvention z);
// Throws std::invalid_argument for a name other than rest or tare.
ZeroConvention zeroConventionFromString(const std::string& name);

// What a model is asked to read: the zero convention, and whether its
// readings are kept as states (needed for channels that are not a fixed
// linear function of the dynamic states: IMU channels, tare offsets that
// depend on the parameters). Without them a model is exactly its linear
// observation of the dynamic states.
struct ReadingSettings {
  ZeroConvention zero = ZeroConvention::kRest;
  bool as_states = false;
};

class MechanicalModel {
 public:
  virtual ~MechanicalModel() = default;

  // Names, tables, channels and contacts: the model's one description (the
  // same object its ModelType returns).
  virtual const ModelDescription& description() const = 0;

  int stateSize() const { return static_cast<int>(stateNames().size()); }
  // The dynamic states (the description's), then one row per channel when
  // the readings are kept as states.
  virtual const std::vector<std::string>& stateNames() const { return description().stateNames(); }
  // States the integrator advances; the rows after them are readings.
  int dynamicStateSize() const { return stateSize() - readingCount(); }
  virtual int readingCount() const { return 0; }
  // False for a channel this model, as built, cannot give (e.g. an IMU
  // channel when its readings are not kept as states).
  virtual bool channelModelled(int /*channel*/) const { return true; }
  virtual ZeroConvention zero() const { return ZeroConvention::kRest; }
  // True for a channel this model takes as an input (road-free models take
  // the suspension readings): it is read, but not predicted.
  virtual bool channelIsInput(int /*channel*/) const { return false; }
  // Road-free models: between model channels (channels x channels), the
  // covariance predicted readings inherit from the noise of the input
  // readings (errors in variables; the channels read the same inputs, so
  // their errors are correlated); an input's noise std is hypot(absolute,
  // relative * reading), one entry per input; mean_accel_z the record's (0:
  // unknown). By sample (the sample's own inputs, those before it for the
  // gyro's angle): a function of the sample index, prepared once (the load
  // weighed by the inputs so far). Null for other models.
  // inputNoiseVariance: the mean of its diagonal over the samples. slopes
  // (optional, channels x 2 inputs): each input's change of the channels by
  // its noise at the sample and at the one before (inputOutputCovarianceAt).
  using SampleInputNoise = std::function<Eigen::MatrixXd(std::size_t sample, Eigen::MatrixXd* slopes)>;
  // Road-free models: how many readings are inputs (inputNoiseBySample's
  // order); 0 for other models.
  virtual int inputCount() const { return 0; }
  virtual SampleInputNoise inputNoiseBySample(const Eigen::VectorXd& /*absolute*/,
                                              const Eigen::VectorXd& /*relative*/,
                                              double /*mean_accel_z*/) const {
    return nullptr;
  }
  virtual Eigen::VectorXd inputNoiseVariance(const Eigen::VectorXd& /*absolute*/,
                                             const Eigen::VectorXd& /*relative*/,
                                             double /*mean_accel_z*/) const {
    return {};
  }

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

  // The parameters change from `from` to `to` with the body where it is (a
  // load put on or taken off at a stop): the state y (one column) is moved
  // to the deviations under `to` that put every mass at the same absolute
  // place, velocities unchanged. Default: y unchanged (a model whose states
  // do not depend on the parameters' equilibrium).
  virtual void carryOver(const Eigen::VectorXd& /*from*/, const Eigen::VectorXd& /*to*/,
                         Eigen::ArrayXXd& /*y*/) const {}

  // Kinks of the model's inputs in (t0, t1) (see RoadInput::breakpoints).
  virtual std::vector<double> breakpoints(double t0, double t1) const = 0;

  // The road the model rides on (nullptr for a model without one), so that a
  // variant of the model (another vehicle) can be built on the same road.
  virtual const ContactRoad* contactRoad() const { return nullptr; }

  // The load transfer ratio (F_right - F_left) / (F_right + F_left) of the
  // tyre loads at time t (a sample's) for the vehicle `params` (one full
  // parameter vector, e.g. the posterior mean), from the readings at t
  // (docs/models.md, "Rollover outputs"). Models that give it say so with
  // hasLoadTransferRatio(); the default: NaN.
  virtual bool hasLoadTransferRatio() const { return false; }
  virtual double loadTransferRatio(const Eigen::VectorXd& /*params*/, double /*t*/) const {
    return std::numeric_limits<double>::quiet_NaN();
  }

  int parameterIndex(const std::string& name) const;  // -1 when unknown
};

// The checks every model on a road makes when it is built (built-in or
// plugin, so they live here once): a road under the description's contacts,
// and the nominal vector admissible by the model's invalidReason (as defined
// by the class under construction). std::invalid_argument prefixed by `who`.
void checkModelOnRoad(const MechanicalModel& model, const ContactRoad* road,
                      const std::string& who);

}  // namespace pc_ekf
