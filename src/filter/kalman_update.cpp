#include "pc_ekf/filter/kalman_update.h"

#include <algorithm>
#include <cmath>
#include <limits>
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
  if (!d.finite) return d;
  // A channel whose predicted variance (spread + noise) is below round-off of
  // its magnitude makes P_zz + R numerically singular: the gain would turn
  // round-off in Z into arbitrary corrections. Refuse the update instead.
  const double eps = std::numeric_limits<double>::epsilon();
  for (Eigen::Index c = 0; c < zc.rows(); ++c) {
    const double variance = zc.row(c).tail(zc.cols() - 1).squaredNorm() + r[c];
    const double scale = std::max(std::abs(zc(c, 0)), std::abs(z[c]));
    if (variance <= eps * scale * scale) {
      d.singular = true;
      d.finite = false;
    }
  }
  return d;
}

// Buffers of pcKalmanUpdate, per thread: the one-step filter calls it at
// every sample with the same sizes, so after the first call it allocates nothing.
struct UpdateWork {
  Eigen::VectorXd rinv, rv, b, weights, s, ts, mean_z, gain_a, gain_y;
  Eigen::MatrixXd c, transform, a, szz, yc;
  Eigen::LLT<Eigen::MatrixXd> inner;
  Eigen::LDLT<Eigen::MatrixXd> innovation_cov;
};

}  // namespace

UpdateDiagnostics pcKalmanUpdate(Eigen::MatrixXd& x, const Eigen::MatrixXd& z_coeffs,
                                 const Eigen::VectorXd& z, const Eigen::VectorXd& r,
                                 UpdateRule rule) {
  UpdateDiagnostics d = prepare(x, z_coeffs, z, r);
  const Eigen::Index k = z.size(), m = x.cols() - 1;
  if (!d.finite || k == 0) return d;
  const auto y = z_coeffs.rightCols(m);
  thread_local UpdateWork w;
  w.rinv = r.cwiseInverse();
  w.rv = w.rinv.cwiseProduct(d.innovation);
  // C = Y^T R^-1 Y, G = (I + C)^-1: the posterior covariance of the higher
  // coefficients' weights (P_a = A G A^T for the joint update). Needed by the
  // paper rule, and for the NIS when there are more observations than terms.
  const bool weight_space = rule == UpdateRule::kPaper || k > m;
  if (weight_space) {
    w.c.noalias() = y.transpose() * w.rinv.asDiagonal() * y;
    w.c.diagonal().array() += 1.0;
    w.inner.compute(w.c);
    // NIS by Woodbury: v^T (Y Y^T + R)^-1 v = v^T R^-1 v - b^T (I + C)^-1 b, b = Y^T R^-1 v.
    w.b.noalias() = y.transpose() * w.rv;
    d.nis = d.innovation.dot(w.rv) - w.b.dot(w.inner.solve(w.b));
  } else {
    // Few observations: v^T (Y Y^T + R)^-1 v directly, a k x k solve.
    w.szz.noalias() = y * y.transpose();
    w.szz.diagonal() += r;
    w.innovation_cov.compute(w.szz);
    d.nis = d.innovation.dot(w.innovation_cov.solve(d.innovation));
  }

  // A <- A T, X_1 <- X_1 + A w.
  if (rule == UpdateRule::kPaper) {
    // K = A G Y^T R^-1 (push-through); A - K Y = A (I - G C) = A G.
    w.weights = w.inner.solve(w.b);
    w.transform = w.inner.solve(Eigen::MatrixXd::Identity(m, m));
  } else if (k <= m) {
    // Few observations (one sample's channels): the serial scalar square root
    // (Whitaker & Hamill 2002) applied directly to A and to the remaining
    // channels' Y, O((rows + k) k S) with no S x S transform.
    w.a = x.rightCols(m);
    w.yc = y;
    w.mean_z = z_coeffs.col(0);
    w.gain_a.resize(x.rows());
    w.gain_y.resize(k);
    for (Eigen::Index ch = 0; ch < k; ++ch) {
      const auto s = w.yc.row(ch);
      const double denom = s.squaredNorm() + r[ch];
      const double residual = z[ch] - w.mean_z[ch];
      w.gain_a.noalias() = w.a * s.transpose();
      w.gain_y.noalias() = w.yc * s.transpose();
      w.gain_a /= denom;
      w.gain_y /= denom;
      x.col(0) += w.gain_a * residual;
      w.mean_z += w.gain_y * residual;
      const double alpha = 1.0 / (1.0 + std::sqrt(r[ch] / denom));
      w.s = alpha * s.transpose();
      w.a.noalias() -= w.gain_a * w.s.transpose();
      w.yc.noalias() -= w.gain_y * w.s.transpose();
    }
    x.rightCols(m) = w.a;
    d.finite = x.allFinite() && std::isfinite(d.nis);
    return d;
  } else {
    // Serial scalar square root (Whitaker & Hamill 2002) carried out on the
    // weights: after channel c, A_c = A T and Z_c = Z_1 + Y w, Y T (many
    // observations: the whole-set update's 4N).
    w.transform.setIdentity(m, m);
    w.weights.setZero(m);
    w.s.resize(m);
    w.ts.resize(m);
    for (Eigen::Index ch = 0; ch < k; ++ch) {
      w.s.noalias() = w.transform.transpose() * y.row(ch).transpose();  // current Y row
      const double var = w.s.squaredNorm();
      const double denom = var + r[ch];
      const double residual = d.innovation[ch] - y.row(ch).dot(w.weights);
      w.ts.noalias() = w.transform * w.s;
      w.weights += w.ts * (residual / denom);
      const double alpha = 1.0 / (1.0 + std::sqrt(r[ch] / denom));
      w.transform.noalias() -= (alpha / denom) * w.ts * w.s.transpose();
    }
  }
  w.a = x.rightCols(m);
  x.col(0).noalias() += w.a * w.weights;
  x.rightCols(m).noalias() = w.a * w.transform;
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
