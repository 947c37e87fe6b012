#include "pc_ekf/filter/serial_noise.h"

#include <stdexcept>

namespace pc_ekf {

double SerialNoise::add(const Eigen::MatrixXd& g, const Eigen::MatrixXd& h,
                        const Eigen::VectorXd& rho) {
  if (g.rows() != h.rows() || g.cols() != h.cols() || rho.size() != g.cols()) {
    throw std::invalid_argument("SerialNoise: slopes and correlations of different sizes");
  }
  // Sample s = k - l before k: Cov(eps_s, eps_k) = p_now, Cov(eps_s, eps_{k-1}) = p_before
  // (products of the rhos in between), and eps_{s-1} one more rho_s back:
  //   C = G_s diag(p_now) G_k' - G_s diag(p_before) H_k'
  //       - H_s diag(rho_s p_now) G_k' + H_s diag(rho_s p_before) H_k'.
  Eigen::ArrayXd p_before = Eigen::ArrayXd::Ones(rho.size());
  Eigen::ArrayXd p_now = rho.array();
  double sum = 0.0;
  for (const Sample& s : recent_) {
    if (s.g.rows() != g.rows() || s.g.cols() != g.cols()) break;  // channels changed: no more
    const Eigen::ArrayXd back_now = s.rho.array() * p_now, back_before = s.rho.array() * p_before;
    const Eigen::MatrixXd c = s.g * (p_now.matrix().asDiagonal() * g.transpose()) -
                              s.g * (p_before.matrix().asDiagonal() * h.transpose()) -
                              s.h * (back_now.matrix().asDiagonal() * g.transpose()) +
                              s.h * (back_before.matrix().asDiagonal() * h.transpose());
    sum += c.squaredNorm();
    p_now = back_now;
    p_before = back_before;
    if (!(p_now.abs().maxCoeff() > 1e-3 || p_before.abs().maxCoeff() > 1e-3)) break;
  }
  recent_.push_front(Sample{g, h, rho});
  while (static_cast<int>(recent_.size()) > max_lags_) recent_.pop_back();
  return 4.0 * sum;
}

}  // namespace pc_ekf
