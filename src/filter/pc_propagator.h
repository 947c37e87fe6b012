// Forecast of the extended PC state X = [y; theta] by stochastic collocation
// (docs/method.md §4.1): evaluate X at the collocation points, integrate each point's
// model, project back onto the basis.
#pragma once

#include <Eigen/Dense>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "pc_ekf/filter/column_workers.h"
#include "pc_ekf/filter/uncertain_parameters.h"
#include "pc_ekf/model/integrator.h"
#include "pc_ekf/model/mechanical_model.h"
#include "pc_ekf/pc/collocation_design.h"
#include "pc_ekf/pc/polynomial_basis.h"

namespace pc_ekf {

// Points whose parameters leave the physical domain or whose integration is
// not finite are dropped from the projection (least squares on the rest) and
// counted here; `ok` is false when too few remain to determine S coefficients.
struct ForecastReport {
  int points = 0;
  int invalid_points = 0;    // parameters outside the model's domain
  int nonfinite_points = 0;  // integration produced NaN/Inf
  bool ok = true;
  std::string first_problem;
  // Relative leave-one-out error of the projection per model channel
  // (CollocationDesign::leaveOneOutError of the channels at the points), for
  // the leading channels the model gives as built (MechanicalModel::
  // channelModelled); empty when a point was dropped or the design has none (Q = S).
  Eigen::VectorXd loo_error;
  void merge(const ForecastReport& other);
};

struct ForecastWork;  // the forecast's per-thread buffers (pc_propagator_forecast.h)

class PcPropagator {
 public:
  // threads: the forecast integrates the collocation points on this many
  // threads (<= 0: the machine's cores); the result is bitwise the same for
  // any count (each point's integration is independent of the others', and
  // designs of kBlockedPoints or more sum over points in fixed blocks).
  PcPropagator(std::shared_ptr<const MechanicalModel> model, const PolynomialBasis& basis,
               const CollocationDesign& design, ParameterMapping mapping,
               IntegratorSettings settings, int threads = 1);

  const MechanicalModel& model() const { return *model_; }
  std::shared_ptr<const MechanicalModel> modelPointer() const { return model_; }
  const PolynomialBasis& basis() const { return basis_; }
  const CollocationDesign& design() const { return design_; }
  const ParameterMapping& mapping() const { return mapping_; }
  const IntegratorSettings& integration() const { return settings_; }
  int stateCount() const { return model_->stateSize(); }
  int parameterCount() const { return mapping_.count(); }
  int termCount() const { return basis_.size(); }

  // Prior X: theta from the config's germs, y the projected initial state.
  Eigen::MatrixXd priorState() const;
  // X for the parameter coefficients theta (count x S): y the projected
  // initial state. Throws std::invalid_argument naming an invalid point.
  Eigen::MatrixXd stateFor(const Eigen::MatrixXd& theta) const;
  // Advances X from t0 to t1 (t1 >= t0; equal times leave X unchanged).
  ForecastReport forecast(Eigen::MatrixXd& x, double t0, double t1) const;

  // Full model parameters at the collocation points for parameter coefficients
  // (count x S), with per-point admissibility (reason "" when valid).
  Eigen::MatrixXd parametersAtPoints(const Eigen::MatrixXd& theta_coeffs,
                                     std::vector<std::string>* invalid_reasons) const;
  // Projects values at the points (rows x Q) onto the basis (rows x S) using
  // only the points marked usable; reports when they cannot determine S terms.
  Eigen::MatrixXd project(const Eigen::MatrixXd& values, const std::vector<bool>& usable,
                          ForecastReport* report) const;

  // The same forecast (bit for bit: the result does not depend on the thread
  // count) on `threads` threads of its own, sharing the model: for a second
  // thread that forecasts while this propagator is in use.
  std::shared_ptr<const PcPropagator> withThreads(int threads) const;

  long integrations() const { return integrations_; }
  int threads() const { return workers_ ? workers_->threads() : 1; }
  // Fewest points of a part of the parallel forecast (two parts per thread,
  // taken by whichever thread is free): below it the hand-off costs more than
  // it saves. Designs under 3 parts' worth stay on one thread.
  static constexpr long kMinPointsPerPart = 16;
  // Designs of this size or more take the blocked forecast on any thread
  // count (one thread included, so that every count gives the same bits).
  static constexpr long kBlockedPoints = 3 * kMinPointsPerPart;
  // Points per block of the blocked forecast's sums (a SIMD multiple).
  static constexpr long kBlock = 16;

 private:
  // The forecast (pc_propagator_forecast.cpp) is one of two algorithms over
  // the same stages. forecastInBlocks gives each thread whole blocks of
  // kBlock points and every per-point step of them (X A^T, preparation,
  // integration, the products with P and the leave-one-out sums), the sums
  // taken per block and the blocks added in order, so that no sum depends on
  // the thread count; it returns false, x untouched, when some point is not
  // usable. forecastDroppingUnusable evaluates the points at once, integrates
  // the usable ones in parts on the threads, projects them in one sum and
  // drops unusable points (least squares on the rest).
  bool forecastInBlocks(Eigen::MatrixXd& x, double t0, double t1, ForecastWork& work,
                        ForecastReport* report) const;
  void forecastDroppingUnusable(Eigen::MatrixXd& x, double t0, double t1, ForecastWork& work,
                                ForecastReport* report) const;
  // Stages both take. 1: X A^T and the full model parameters of the points
  // [begin, end) (work.at_points, work.params).
  void evaluatePoints(const Eigen::MatrixXd& x, Eigen::Index begin, Eigen::Index end,
                      ForecastWork& work) const;
  // 3: the models of the points (columns of `params`) from t0 to t1, states `y`.
  void integratePoints(const Eigen::MatrixXd& params, Eigen::ArrayXXd& y, double t0,
                       double t1) const;
  // 4: block b's share Y_b P_b^T of the projection, for the nq points from q0
  // (their states' columns from y_cols), into work.state_sums.
  void projectBlock(Eigen::Index b, Eigen::Index q0, Eigen::Index nq, const double* y_cols,
                    ForecastWork& work) const;
  // forecastInBlocks' steps: a block's sums (4 and the channels' sums for 5),
  // and 5, the channels' leave-one-out error from the blocks' sums.
  void sumBlock(Eigen::Index b, ForecastWork& work) const;
  void leaveOneOutInBlocks(const Eigen::MatrixXd& x, ForecastWork& work,
                           ForecastReport* report) const;
  void runParts(const std::vector<long>& bounds,
                const std::function<void(int, long, long)>& job) const;

  std::shared_ptr<const MechanicalModel> model_;
  PolynomialBasis basis_;
  CollocationDesign design_;
  ParameterMapping mapping_;
  IntegratorSettings settings_;
  // H's rows of the leading channels the model gives as built (the
  // leave-one-out error's channels; all of them with readings as states).
  Eigen::MatrixXd loo_observation_;
  std::shared_ptr<ColumnWorkers> workers_;  // null: one thread
  mutable long integrations_ = 0;  // point-intervals integrated (cost accounting)
};

}  // namespace pc_ekf
