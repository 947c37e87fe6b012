#include "pc_ekf/filter/prior_correction.h"

namespace pc_ekf {

Eigen::MatrixXd scaledCovariance(const Eigen::MatrixXd& c, const Eigen::VectorXd& scale) {
  const Eigen::MatrixXd a = scale.cwiseInverse().asDiagonal() * c.rightCols(c.cols() - 1);
  return a * a.transpose();
}

Eigen::VectorXd priorScale(const Eigen::MatrixXd& prior) {
  Eigen::VectorXd scale(prior.rows());
  for (Eigen::Index i = 0; i < prior.rows(); ++i) {
    const double sd = prior.row(i).tail(prior.cols() - 1).norm();
    scale[i] = sd > 0.0 ? sd : 1.0;
  }
  return scale;
}

bool mapOntoMoments(Eigen::MatrixXd& coefficients, const Eigen::VectorXd& mean,
                    const Eigen::MatrixXd& covariance, const Eigen::VectorXd& scale) {
  const Eigen::LLT<Eigen::MatrixXd> pq(scaledCovariance(coefficients, scale));
  const Eigen::LLT<Eigen::MatrixXd> pf(covariance);
  if (pq.info() != Eigen::Success || pf.info() != Eigen::Success) return false;
  const Eigen::MatrixXd eye = Eigen::MatrixXd::Identity(mean.size(), mean.size());
  const Eigen::MatrixXd t = Eigen::MatrixXd(pf.matrixL()) * pq.matrixL().solve(eye);
  const Eigen::MatrixXd rest =
      scale.cwiseInverse().asDiagonal() * coefficients.rightCols(coefficients.cols() - 1);
  coefficients.rightCols(coefficients.cols() - 1) = scale.asDiagonal() * (t * rest);
  coefficients.col(0) = scale.cwiseProduct(mean);
  return true;
}

bool correctForPrior(const Eigen::MatrixXd& prior, const Eigen::MatrixXd& working,
                     Eigen::MatrixXd& posterior) {
  const Eigen::Index n = prior.rows();
  // Units of the prior's std: the three covariances span many decades.
  const Eigen::VectorXd scale = priorScale(prior);
  const Eigen::LLT<Eigen::MatrixXd> p0(scaledCovariance(prior, scale));
  const Eigen::LLT<Eigen::MatrixXd> q(scaledCovariance(working, scale));
  const Eigen::MatrixXd pq_cov = scaledCovariance(posterior, scale);
  const Eigen::LLT<Eigen::MatrixXd> pq(pq_cov);
  if (p0.info() != Eigen::Success || q.info() != Eigen::Success || pq.info() != Eigen::Success) {
    return false;
  }
  const Eigen::MatrixXd eye = Eigen::MatrixXd::Identity(n, n);
  const Eigen::MatrixXd p0_inv = p0.solve(eye), q_inv = q.solve(eye), pq_inv = pq.solve(eye);
  Eigen::MatrixXd d = pq_inv - q_inv;
  d = 0.5 * (d + d.transpose());
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(d);
  d = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() *
      eig.eigenvectors().transpose();
  const Eigen::MatrixXd information = d + p0_inv;
  const Eigen::LLT<Eigen::MatrixXd> info(information);
  if (info.info() != Eigen::Success) return false;
  const Eigen::MatrixXd p = info.solve(eye);
  const auto mean = [&](const Eigen::MatrixXd& c) {
    return Eigen::VectorXd(c.col(0).cwiseQuotient(scale));
  };
  // The data's share of the information vector, D m_data = P_q^-1 m_q - Q^-1 q.
  const Eigen::VectorXd b = pq_inv * mean(posterior) - q_inv * mean(working) + p0_inv * mean(prior);
  const Eigen::VectorXd m = p * b;
  return mapOntoMoments(posterior, m, p, scale);
}

}  // namespace pc_ekf
