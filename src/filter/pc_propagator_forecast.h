// The forecast's per-thread buffers, shared by its two algorithms and their
// stages (pc_propagator_forecast.cpp); internal to PcPropagator's forecast.
#pragma once

#include <string>
#include <vector>

#include "pc_ekf/filter/pc_propagator.h"

namespace pc_ekf {

// The caller's buffers (parts on other threads write disjoint columns of
// them): the per-sample path allocates nothing once they have their size
// (the propagator is shared, e.g. by the node's filters).
struct ForecastWork {
  Eigen::MatrixXd at_points;  // (states + parameters) x Q
  Eigen::MatrixXd params;     // model parameters x Q
  Eigen::ArrayXXd y;          // states x (usable points), integrated
  std::vector<std::string> reasons;
  std::vector<bool> usable;
  std::vector<Eigen::Index> cols;  // forecastDroppingUnusable: the usable points
  Eigen::MatrixXd z;               // channels x Q: H y
  Eigen::MatrixXd state_sums;      // states x (S blocks): Y_b P_b^T of block b
  Eigen::MatrixXd channel_sums;    // channels x (S blocks): Z_b pinv(A)_b^T (quadrature)
  // channels x blocks: sum z, sum z^2, sum of squared leave-one-out errors,
  // sum (z - mean)^2.
  Eigen::MatrixXd sum, sum_sq, err_sq, spread;
  Eigen::MatrixXd coeffs;  // channels x S: the least-squares fit of z
  Eigen::ArrayXd mean;
  std::vector<char> unusable;  // forecastInBlocks: per part
  std::vector<long> bounds;
};

// Block b's sums among per-block sums laid side by side (rows x S each).
inline Eigen::Map<const Eigen::MatrixXd> blockSums(const Eigen::MatrixXd& sums, Eigen::Index rows,
                                                   Eigen::Index s_count, Eigen::Index b) {
  return Eigen::Map<const Eigen::MatrixXd>(sums.data() + b * s_count * rows, rows, s_count);
}

}  // namespace pc_ekf
