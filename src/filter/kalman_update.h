// The PC Kalman update of docs/method.md §4.2-§4.4, done in the (S-1)-dimensional space
// of the higher PC coefficients so its cost is linear in the number of
// observations (one sample's channels or a whole stacked record).
//
// Notation: X (rows x S) coefficients of what is updated, column 0 the mean;
// Z (k x S) coefficients of the predicted observations; A = X[:,1:],
// Y = Z[:,1:]; P_xz = A Y^T, P_zz = Y Y^T, R = diag(r).
#pragma once

#include <Eigen/Dense>
#include <string>

namespace pc_ekf {

enum class UpdateRule {
  kPaper,       // paper eq. 28-32: X_j <- (I - K H) X_j, covariance (I-KH)P(I-KH)^T
  kSquareRoot,  // serial Whitaker-Hamill square root, covariance (I-KH)P (docs/method.md §4.3)
};
std::string toString(UpdateRule u);
UpdateRule updateRuleFromString(const std::string& s);  // throws std::invalid_argument

struct UpdateDiagnostics {
  Eigen::VectorXd innovation;  // z - Z[:,0]
  double nis = 0.0;            // innovation^T (P_zz + R)^-1 innovation
  int channels = 0;
  bool finite = true;          // false when the inputs or the result are not finite
  // P_zz + R numerically singular (a channel's predicted std below sqrt(eps)
  // of its magnitude, e.g. zero noise on a channel the parameters do not
  // move): the update is refused, X untouched, finite = false.
  bool singular = false;
};

// Updates X in place given the data z (k), noise variances r (k, > 0) and the
// observation coefficients Z. Equivalent to the state-space formulas:
//   paper:       K = P_xz (P_zz + R)^-1, X_1 += K (z - Z_1), X_j -= K Z_j
//   square_root: channels processed one at a time in the given order with
//                alpha = 1 / (1 + sqrt(r_c / (var_c + r_c))), X_j -= alpha K Z_j,
//                the remaining channels' Z updated alongside.
// Cost O(k S^2 + rows S^2); never forms a k x k matrix.
UpdateDiagnostics pcKalmanUpdate(Eigen::MatrixXd& x, const Eigen::MatrixXd& z_coeffs,
                                 const Eigen::VectorXd& z, const Eigen::VectorXd& r,
                                 UpdateRule rule);

// The dense textbook formulas (k x k solve) for tests and small cases.
UpdateDiagnostics pcKalmanUpdateDense(Eigen::MatrixXd& x, const Eigen::MatrixXd& z_coeffs,
                                      const Eigen::VectorXd& z, const Eigen::VectorXd& r,
                                      UpdateRule rule);

}  // namespace pc_ekf
