// Errors in variables for road-free models (docs/method.md §4.10): the
// variance a predicted reading inherits from the noise of the readings used
// as inputs, to first order, averaged over a record.
#pragma once

#include <Eigen/Dense>
#include <functional>
#include <vector>

#include "pc_ekf/model/reading_inputs.h"

namespace pc_ekf {

// The outputs of one parameter point at a sample: `now` and `before` the
// inputs at the sample and at the previous one (`at_rest`: none before it),
// dt between them, `attitude` the offsets of the integrated inputs (one per
// entry of `integrated` in inputOutputVariance), written to `out`.
using ReadingOutputs = std::function<void(const double* now, const double* before, bool at_rest,
                                          double dt, const double* attitude, double* out)>;

// At sample k of `inputs`: each input at k and at k - 1 perturbed by its
// noise there, hypot(absolute, relative * reading), and each integrated
// input (e.g. a gyro's angle) by absolute * sqrt(dt * t_k) (the random walk
// of its integral up to t_k), one at a time (central differences). The noise
// of an input at k and at k - 1 is correlated by inputs.noiseCorrelation
// (0: independent). Returns the covariance of the summed changes between
// the outputs (outputs x outputs): one input's noise moves every output that
// reads it, so the outputs' errors are correlated. slopes (optional,
// outputs x 2 inputs): each input's change of the outputs by its noise at
// k (first inputs.count() columns) and at k - 1 (the rest), the derivative
// times that noise's std; the integrated inputs' walks are not in it.
Eigen::MatrixXd inputOutputCovarianceAt(const ReadingInputs& inputs, std::size_t k,
                                        const Eigen::VectorXd& absolute,
                                        const Eigen::VectorXd& relative,
                                        const std::vector<int>& integrated, int outputs,
                                        const ReadingOutputs& evaluate,
                                        Eigen::MatrixXd* slopes = nullptr);

// The mean of the diagonal of `at` (per model channel, `channels` square)
// over samples 0..n-1 (a whole record: none forgotten).
Eigen::VectorXd meanVarianceOverSamples(const std::function<Eigen::MatrixXd(std::size_t)>& at,
                                        std::size_t samples, int channels);

// The load a tare record weighs: the springs' mean force over the samples
// (inputs.sampleSum(spring_force_sum): the springs' force at each sample's
// inputs, summed as they came) over the record's mean accel_z, less the
// body mass, clamped to [0, limit]; `fallback` when it cannot be told.
double weighedLoad(const ReadingInputs& inputs, int spring_force_sum, double mean_accel_z,
                   double body_mass, double limit, double fallback);

}  // namespace pc_ekf
