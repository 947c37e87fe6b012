// Noise that consecutive samples share. Road-free, a sample's prediction
// reads inputs (travels, rates, gyros) at this sample and at the one before,
// a blended travel's noise is low-passed (lag-1 correlation rho), and a gyro
// read as an input at the sample before is read as an output at that sample:
// the whitened residuals of neighbouring samples are correlated although
// each sample's own are not. Their normalised sum of squares T keeps its
// mean (the entries) but its variance grows beyond 2 per entry by
//   4 sum_k sum_{l >= 1} || C(k - l, k) ||_F^2,
// C the whitened cross-covariance of the two samples' residuals. The
// posterior-predictive check takes that variance (Measurement::serial_variance).
//
// A sample's residual loads its inputs' standardised noise eps_k and
// eps_{k-1} as r_k = A_k eps_k - B_k eps_{k-1}: A = D - N (D: the output's
// own sensor noise where the output is also an input; N, B: the
// prediction's slopes, RoadFreeStream's input slopes), each input's noise
// AR(1) with its correlation rho to the sample before.
#pragma once

#include <Eigen/Dense>
#include <deque>

namespace pc_ekf {

class SerialNoise {
 public:
  // Lags beyond which the shared noise is below 1e-3 of its variance are
  // left out, and at most `max_lags` are kept.
  explicit SerialNoise(int max_lags = 64) : max_lags_(max_lags) {}
  void reset() { recent_.clear(); }
  // g = W A, h = W B (values x inputs, W the sample's whitening), rho: each
  // input's noise correlation with the sample before. Returns this sample's
  // share of T's variance beyond 2 per entry, against the samples before.
  double add(const Eigen::MatrixXd& g, const Eigen::MatrixXd& h, const Eigen::VectorXd& rho);

 private:
  struct Sample {
    Eigen::MatrixXd g, h;
    Eigen::VectorXd rho;
  };
  int max_lags_;
  std::deque<Sample> recent_;  // newest first
};

}  // namespace pc_ekf
