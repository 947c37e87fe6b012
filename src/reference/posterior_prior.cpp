#include "pc_ekf/reference/posterior_prior.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace pc_ekf {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kTailQuantile = 1e-6;

}  // namespace

PriorDensity::PriorDensity(const std::vector<GermSpec>& germs) : germs_(germs) {
  if (germs_.empty()) throw std::invalid_argument("PriorDensity: no germs");
  for (const GermSpec& g : germs_) {
    families_.emplace_back(g);
    const OrthonormalFamily& f = families_.back();
    GermInterval s{f.lower(), f.upper()};
    GermInterval r = s;
    if (!std::isfinite(r.lower)) r.lower = f.inverseCdf(kTailQuantile);
    if (!std::isfinite(r.upper)) r.upper = f.inverseCdf(1.0 - kTailQuantile);
    support_.push_back(s);
    range_.push_back(r);
  }
}

double PriorDensity::logDensity(const Eigen::Ref<const Eigen::VectorXd>& xi) const {
  double sum = 0.0;
  for (int i = 0; i < dimension(); ++i) {
    const double x = xi[i];
    if (!(x >= support_[i].lower && x <= support_[i].upper)) return -kInf;
    const double p = families_[i].pdf(x);
    if (!(p > 0.0) || !std::isfinite(p)) return -kInf;
    sum += std::log(p);
  }
  return sum;
}

Eigen::VectorXd PriorDensity::logDensities(const Eigen::MatrixXd& xi) const {
  Eigen::VectorXd out(xi.cols());
  for (Eigen::Index j = 0; j < xi.cols(); ++j) out[j] = logDensity(xi.col(j));
  return out;
}

void PriorDensity::derivatives(const Eigen::Ref<const Eigen::VectorXd>& xi,
                               Eigen::VectorXd& gradient, Eigen::VectorXd& curvature) const {
  gradient = Eigen::VectorXd::Zero(dimension());
  curvature = Eigen::VectorXd::Zero(dimension());
  for (int i = 0; i < dimension(); ++i) {
    const double x = xi[i];
    const GermSpec& g = germs_[i];
    double d1 = 0.0, d2 = 0.0;  // first and second derivative of log pdf
    switch (g.family) {
      case GermFamily::kBeta: {  // (a-1) log(1+x) + (b-1) log(1-x)
        const double p = 1.0 + x, q = 1.0 - x;
        if (p > 0.0 && q > 0.0) {
          d1 = (g.alpha - 1.0) / p - (g.beta - 1.0) / q;
          d2 = -(g.alpha - 1.0) / (p * p) - (g.beta - 1.0) / (q * q);
        }
        break;
      }
      case GermFamily::kUniform:
        break;
      case GermFamily::kGaussian:
        d1 = -x;
        d2 = -1.0;
        break;
      case GermFamily::kGamma:  // (k-1) log x - x
        if (x > 0.0) {
          d1 = (g.alpha - 1.0) / x - 1.0;
          d2 = -(g.alpha - 1.0) / (x * x);
        }
        break;
    }
    gradient[i] = d1;
    curvature[i] = std::max(0.0, -d2);
  }
}

Eigen::VectorXd PriorDensity::clamp(const Eigen::Ref<const Eigen::VectorXd>& xi) const {
  Eigen::VectorXd out = xi;
  for (int i = 0; i < dimension(); ++i) {
    out[i] = std::min(std::max(out[i], support_[i].lower), support_[i].upper);
  }
  return out;
}

}  // namespace pc_ekf
