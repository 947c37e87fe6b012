#include "filter/kalman_update.h"

#include <cmath>
#include <stdexcept>

namespace pc_ekf {

std::string toString(UpdateRule u) { return u == UpdateRule::kPaper ? "paper" : "square_root"; }

UpdateRule updateRuleFromString(const std::string& s) {
  if (s == "paper") return UpdateRule::kPaper;
  if (s == "square_root") return UpdateRule::kSquareRoot;
  throw std::invalid_argument("update rule '" + s + "' unknown, expected paper or square_root");
}

namespace {

// Checks sizes (throws) and finiteness; fills the innovation and channel count.
UpdateDiagnostics prepare(const Eigen::MatrixXd& x, const Eigen::MatrixXd& zc,
                          const Eigen::VectorXd& z, const Eigen::VectorXd& r) {
  if (zc.cols() != x.cols() || zc.rows() != z.size() || r.size() != z.size() || x.cols() < 1) {
    throw std::invalid_argument("pcKalmanUpdate: inconsistent sizes");
  }
  UpdateDiagnostics d;
  d.channels = static_cast<int>(z.size());
  d.innovation = z - zc.col(0);
  d.finite = x.allFinite() && zc.allFinite() && z.allFinite() && r.allFinite() &&
             (r.array() > 0.0).all();
  return d;
}

// NIS by Woodbury: v^T (Y Y^T + R)^-1 v = v^T R^-1 v - b^T (I + Y^T R^-1 Y)^-1 b, b = Y^T R^-1 v.
double woodburyNis(const Eigen::MatrixXd& y, const Eigen::VectorXd& rinv, const Eigen::VectorXd& v,
                   const Eigen::LLT<Eigen::MatrixXd>& inner) {
  const Eigen::VectorXd rv = rinv.cwiseProduct(v);
  const Eigen::VectorXd b = y.transpose() * rv;
  return v.dot(rv) - b.dot(inner.solve(b));
}

}  // namespace

UpdateDiagnostics pcKalmanUpdate(Eigen::MatrixXd& x, const Eigen::MatrixXd& z_coeffs,
                                 const Eigen::VectorXd& z, const Eigen::VectorXd& r,
                                 UpdateRule rule) {
  UpdateDiagnostics d = prepare(x, z_coeffs, z, r);
  const Eigen::Index k = z.size(), m = x.cols() - 1;
  if (!d.finite || k == 0) return d;
  const auto y = z_coeffs.rightCols(m);
  const Eigen::VectorXd rinv = r.cwiseInverse();
  // C = Y^T R^-1 Y, G = (I + C)^-1: the posterior covariance of the higher
  // coefficients' weights (P_a = A G A^T for the joint update).
  Eigen::MatrixXd c = y.transpose() * rinv.asDiagonal() * y;
  Eigen::MatrixXd inner = Eigen::MatrixXd::Identity(m, m) + c;
  const Eigen::LLT<Eigen::MatrixXd> llt(inner);
  d.nis = woodburyNis(y, rinv, d.innovation, llt);

  Eigen::MatrixXd transform;  // A <- A T
  Eigen::VectorXd weights;    // X_1 <- X_1 + A w
  if (rule == UpdateRule::kPaper) {
    // K = A G Y^T R^-1 (push-through); A - K Y = A (I - G C) = A G.
    weights = llt.solve(y.transpose() * rinv.cwiseProduct(d.innovation));
    transform = llt.solve(Eigen::MatrixXd::Identity(m, m));
  } else {
    // Serial scalar square root (Whitaker & Hamill 2002) carried out on the
    // weights: after channel c, A_c = A T and Z_c = Z_1 + Y w, Y T.
    transform = Eigen::MatrixXd::Identity(m, m);
    weights = Eigen::VectorXd::Zero(m);
    Eigen::VectorXd s(m), ts(m);
    for (Eigen::Index ch = 0; ch < k; ++ch) {
      s.noalias() = transform.transpose() * y.row(ch).transpose();  // current Y row
      const double var = s.squaredNorm();
      const double denom = var + r[ch];
      const double residual = d.innovation[ch] - y.row(ch).dot(weights);
      ts.noalias() = transform * s;
      weights += ts * (residual / denom);
      const double alpha = 1.0 / (1.0 + std::sqrt(r[ch] / denom));
      transform.noalias() -= (alpha / denom) * ts * s.transpose();
    }
  }
  const Eigen::MatrixXd a = x.rightCols(m);
  x.col(0) += a * weights;
  x.rightCols(m) = a * transform;
  d.finite = x.allFinite() && std::isfinite(d.nis);
  return d;
}

UpdateDiagnostics pcKalmanUpdateDense(Eigen::MatrixXd& x, const Eigen::MatrixXd& z_coeffs,
                                      const Eigen::VectorXd& z, const Eigen::VectorXd& r,
                                      UpdateRule rule) {
  UpdateDiagnostics d = prepare(x, z_coeffs, z, r);
  const Eigen::Index k = z.size(), m = x.cols() - 1;
  if (!d.finite || k == 0) return d;
  Eigen::MatrixXd xa = x, za = z_coeffs;
  if (rule == UpdateRule::kPaper) {
    const Eigen::MatrixXd a = xa.rightCols(m), y = za.rightCols(m);
    const Eigen::MatrixXd szz = y * y.transpose() + Eigen::MatrixXd(r.asDiagonal());
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(szz);
    const Eigen::MatrixXd gain = ldlt.solve(y * a.transpose()).transpose();  // K = P_xz S^-1
    d.nis = d.innovation.dot(ldlt.solve(d.innovation));
    xa.col(0) += gain * d.innovation;
    xa.rightCols(m) -= gain * y;
  } else {
    // State-space serial processing on the augmented [X; Z].
    Eigen::MatrixXd w(xa.rows() + k, xa.cols());
    w << xa, za;
    const Eigen::MatrixXd y0 = za.rightCols(m);
    d.nis = d.innovation.dot(
        (y0 * y0.transpose() + Eigen::MatrixXd(r.asDiagonal())).ldlt().solve(d.innovation));
    for (Eigen::Index ch = 0; ch < k; ++ch) {
      const Eigen::Index row = xa.rows() + ch;
      const Eigen::RowVectorXd s = w.row(row).tail(m);
      const double denom = s.squaredNorm() + r[ch];
      const Eigen::VectorXd gain = w.rightCols(m) * s.transpose() / denom;
      const double residual = z[ch] - w(row, 0);
      w.col(0) += gain * residual;
      const double alpha = 1.0 / (1.0 + std::sqrt(r[ch] / denom));
      w.rightCols(m) -= alpha * gain * s;
    }
    xa = w.topRows(xa.rows());
  }
  x = xa;
  d.finite = x.allFinite();
  return d;
}

}  // namespace pc_ekf
