// The one-step filter's report with its working prior's information replaced
// by the prior's (filter.relinearize.prior_correction, docs/method.md §4.9).
// After a re-linearisation the filter's state is the posterior under a working
// prior q (narrow, centred by the data); the posterior under the prior p0 is,
// Gaussian in the parameters,
//   P^-1 = P_q^-1 - Q^-1 + P0^-1,   P^-1 m = P_q^-1 m_q - Q^-1 q + P0^-1 m0,
// the data's information D = P_q^-1 - Q^-1 clipped at 0 (a direction the
// linear update widened beyond q carries none). The expansion is mapped
// affinely, coefficients' covariance P_q -> P, so its shape is kept.
#pragma once

#include <Eigen/Dense>

namespace pc_ekf {

// prior, working, posterior: parameter coefficients (parameters x S, the
// constant term first, an orthonormal basis). Returns the corrected
// posterior coefficients; false (posterior left as is) when a covariance is
// not positive definite.
bool correctForPrior(const Eigen::MatrixXd& prior, const Eigen::MatrixXd& working,
                     Eigen::MatrixXd& posterior);

// Shared with local_covariance.h. Per parameter, the prior's std (1 where it
// is 0): the units the covariances are handled in (they span many decades).
Eigen::VectorXd priorScale(const Eigen::MatrixXd& prior);
// Covariance of an expansion in those units (orthonormal basis: the
// non-constant coefficients' Gram matrix).
Eigen::MatrixXd scaledCovariance(const Eigen::MatrixXd& coefficients, const Eigen::VectorXd& scale);
// Maps the expansion affinely onto mean `mean` and covariance `covariance`
// (both in units of `scale`), keeping its shape: T = L_P L_Pq^-1 on the
// non-constant coefficients. False (left as is) when a covariance is not
// positive definite.
bool mapOntoMoments(Eigen::MatrixXd& coefficients, const Eigen::VectorXd& mean,
                    const Eigen::MatrixXd& covariance, const Eigen::VectorXd& scale);

}  // namespace pc_ekf
