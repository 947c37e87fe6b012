// Simulation of many parameter sets through a measurement record: the common
// kernel of the whole-set forecast, EnKF, synthetic data and the grid posterior.
#pragma once

#include <Eigen/Dense>
#include <vector>

#include "pc_ekf/filter/measurement.h"
#include "pc_ekf/model/integrator.h"
#include "pc_ekf/model/mechanical_model.h"

namespace pc_ekf {

// Simulates every column of `params` (model parameters x Q) from the model's
// initial state at t = 0 and returns, per time, all channels at every point
// (channels x Q). Times must be non-decreasing and >= 0. Non-finite results
// stay non-finite for the caller to report.
std::vector<Eigen::MatrixXd> simulateChannels(const MechanicalModel& model,
                                              const Eigen::MatrixXd& params,
                                              const std::vector<double>& times,
                                              const IntegratorSettings& settings);

// Same, split over `threads` worker threads by columns (results identical).
std::vector<Eigen::MatrixXd> simulateChannelsParallel(const MechanicalModel& model,
                                                      const Eigen::MatrixXd& params,
                                                      const std::vector<double>& times,
                                                      const IntegratorSettings& settings,
                                                      int threads);

// simulateChannels for a few columns whose later readings take the roll and
// lateral offsets (ModelBatch::offsetPoints, one per column) into *out. False
// when the model takes no offsets.
bool simulateChannelsWithOffsets(const MechanicalModel& model, const Eigen::MatrixXd& params,
                                 const std::vector<double>& times,
                                 const IntegratorSettings& settings, const Eigen::VectorXd& roll,
                                 const Eigen::VectorXd& lateral, std::vector<Eigen::MatrixXd>* out);

std::vector<double> sampleTimes(const MeasurementSeries& series);

}  // namespace pc_ekf
