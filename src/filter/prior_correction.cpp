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
  const Eigen::MatrixXd& v = eig.eigenvectors();
  d = v * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * v.transpose();
  // The directions in which the data carry information (not clipped).
  const Eigen::VectorXd informed = (eig.eigenvalues().array() > 0.0).cast<double>().matrix();
  const Eigen::MatrixXd information = d + p0_inv;
  const Eigen::LLT<Eigen::MatrixXd> info(information);
  if (info.info() != Eigen::Success) return false;
  const Eigen::MatrixXd p = info.solve(eye);
  const auto mean = [&](const Eigen::MatrixXd& c) {
    return Eigen::VectorXd(c.col(0).cwiseQuotient(scale));
  };
  // The data's share of the information vector, D m_data = P_q^-1 m_q - Q^-1 q,
  // kept in the directions D keeps: in a clipped one (the posterior wider than
  // q there, as a parameter walk makes it) the data carry no information, and
  // its share there would move the mean by what the widening did (a road-told
  // run with filter.drift_relative flipped every mass and stiffness to -3.1x).
  const Eigen::VectorXd data =
      v * informed.asDiagonal() * v.transpose() * (pq_inv * mean(posterior) - q_inv * mean(working));
  const Eigen::VectorXd b = data + p0_inv * mean(prior);
  const Eigen::VectorXd m = p * b;
  return mapOntoMoments(posterior, m, p, scale);
}

}  // namespace pc_ekf
