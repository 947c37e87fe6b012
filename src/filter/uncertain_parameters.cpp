#include "pc_ekf/filter/uncertain_parameters.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include "pc_ekf/pc/orthonormal_family.h"

namespace pc_ekf {

ParameterMapping::ParameterMapping(const MechanicalModel& model,
                                   std::vector<UncertainParameter> uncertain)
    : nominal_full_(model.nominalParameters()),
      model_names_(model.parameterNames()),
      uncertain_(std::move(uncertain)) {
  for (const auto& u : uncertain_) {
    const int i = model.parameterIndex(u.name);
    if (i < 0) throw std::invalid_argument("uncertain parameter '" + u.name + "' is not a model parameter");
    index_.push_back(i);
  }
}

std::vector<GermSpec> ParameterMapping::germs() const {
  std::vector<GermSpec> g;
  for (const auto& u : uncertain_) g.push_back(u.germ);
  return g;
}

std::vector<std::string> ParameterMapping::names() const {
  std::vector<std::string> n;
  for (const auto& u : uncertain_) n.push_back(u.name);
  return n;
}

Eigen::MatrixXd ParameterMapping::fullParameters(const Eigen::MatrixXd& theta) const {
  Eigen::MatrixXd full(nominal_full_.size(), theta.cols());
  fillFullParameters(theta, 0, theta.cols(), full);
  return full;
}

void ParameterMapping::fillFullParameters(const Eigen::Ref<const Eigen::MatrixXd>& theta,
                                          Eigen::Index begin, Eigen::Index end,
                                          Eigen::MatrixXd& full) const {
  for (Eigen::Index q = begin; q < end; ++q) {
    full.col(q) = nominal_full_;  // column copies: Eigen's replicate() divides per element
    for (int i = 0; i < count(); ++i) full(index_[i], q) = theta(i, q);
  }
}

Eigen::MatrixXd ParameterMapping::valuesAtGerms(const Eigen::MatrixXd& xi) const {
  Eigen::MatrixXd v(count(), xi.rows());
  for (int i = 0; i < count(); ++i) {
    const auto& u = uncertain_[i];
    v.row(i) = (u.nominal * (1.0 + u.relative_range * xi.col(i).array())).matrix().transpose();
  }
  return v;
}

Eigen::VectorXd ParameterMapping::germOf(const Eigen::VectorXd& values) const {
  Eigen::VectorXd xi(count());
  for (int i = 0; i < count(); ++i) {
    const auto& u = uncertain_[i];
    xi[i] = (values[i] / u.nominal - 1.0) / u.relative_range;
  }
  return xi;
}

Eigen::MatrixXd ParameterMapping::priorCoefficients(const PolynomialBasis& basis) const {
  // xi_d = a_0 + sqrt(b_1) psi_{e_d} (first orthonormal polynomial), so the
  // affine prior needs only the constant and the degree-1 term of its germ.
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(count(), basis.size());
  const auto& idx = basis.multiIndices();
  for (int i = 0; i < count(); ++i) {
    const auto& u = uncertain_[i];
    const OrthonormalFamily& f = basis.family(i);
    const double scale = u.nominal * u.relative_range;
    c(i, 0) = u.nominal + scale * f.recurrenceA(0);
    if (basis.order() < 1) continue;
    for (int j = 1; j < basis.size(); ++j) {
      int degree = 0;
      for (int e : idx[j]) degree += e;
      if (degree == 1 && idx[j][i] == 1) c(i, j) = scale * std::sqrt(f.recurrenceB(1));
    }
  }
  return c;
}

Eigen::MatrixXd ParameterMapping::workingCoefficients(const PolynomialBasis& basis,
                                                      const Eigen::VectorXd& mean,
                                                      const Eigen::VectorXd& stddev,
                                                      bool recentre) const {
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(count(), basis.size());
  const auto& idx = basis.multiIndices();
  for (int i = 0; i < count(); ++i) {
    const OrthonormalFamily& f = basis.family(i);
    // value = mean + s psi_{e_i}, psi_{e_i} = (xi - a_0) / sqrt(b_1) on [lo, hi].
    const double a0 = f.recurrenceA(0), sd = std::sqrt(f.recurrenceB(1));
    const double lo = (f.lower() - a0) / sd, hi = (f.upper() - a0) / sd;
    double m = mean[i], s = stddev[i];
    constexpr double kInside = 0.999;  // the support's ends stay strictly inside
    if (recentre) {
      const double room = upperBound(i) - lowerBound(i);
      if (std::isfinite(lo) && std::isfinite(hi)) s = std::min(s, kInside * room / (hi - lo));
      if (std::isfinite(lo)) m = std::max(m, lowerBound(i) - s * lo / kInside);
      if (std::isfinite(hi)) m = std::min(m, upperBound(i) - s * hi / kInside);
    }
    const double room_below = m - lowerBound(i), room_above = upperBound(i) - m;
    if (!(room_below > 0.0 && room_above > 0.0)) continue;  // row left zero
    if (std::isfinite(lo)) s = std::min(s, kInside * room_below / -lo);
    if (std::isfinite(hi)) s = std::min(s, kInside * room_above / hi);
    c(i, 0) = m;
    for (int j = 1; j < basis.size() && basis.order() >= 1; ++j) {
      int degree = 0;
      for (int e : idx[j]) degree += e;
      if (degree == 1 && idx[j][i] == 1) c(i, j) = s;
    }
  }
  return c;
}

double ParameterMapping::lowerBound(int i) const {
  const auto& u = uncertain_[i];
  const OrthonormalFamily f(u.germ);
  const double a = u.nominal * (1.0 + u.relative_range * f.lower());
  const double b = u.nominal * (1.0 + u.relative_range * f.upper());
  return std::isnan(a) ? -std::numeric_limits<double>::infinity() : std::min(a, b);
}

double ParameterMapping::upperBound(int i) const {
  const auto& u = uncertain_[i];
  const OrthonormalFamily f(u.germ);
  const double a = u.nominal * (1.0 + u.relative_range * f.lower());
  const double b = u.nominal * (1.0 + u.relative_range * f.upper());
  return std::isnan(b) ? std::numeric_limits<double>::infinity() : std::max(a, b);
}

}  // namespace pc_ekf
