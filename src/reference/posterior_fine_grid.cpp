#include "pc_ekf/reference/posterior_fine_grid.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace pc_ekf {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr Eigen::Index kBatch = 4096;
// Nodes lighter than this fraction of the heaviest set no histogram range.
constexpr double kHistogramRangeMass = 1e-10;

// log sum(w * exp(l)) over the selected entries, -inf when all are zero.
double logSumExp(const Eigen::VectorXd& l, const Eigen::VectorXd& w) {
  double peak = -kInf;
  for (Eigen::Index j = 0; j < l.size(); ++j) {
    if (w[j] > 0.0) peak = std::max(peak, l[j]);
  }
  if (!std::isfinite(peak)) return -kInf;
  double sum = 0.0;
  for (Eigen::Index j = 0; j < l.size(); ++j) {
    if (w[j] > 0.0) sum += w[j] * std::exp(l[j] - peak);
  }
  return peak + std::log(sum);
}

Eigen::Index power(int base, int exponent) {
  Eigen::Index p = 1;
  for (int i = 0; i < exponent; ++i) p *= base;
  return p;
}

// Evaluates one grid of the given half-widths; fills everything but the bookkeeping.
void evaluateGrid(const PosteriorResidual& residual, const PriorDensity& prior,
                  const std::vector<FineGridBox>& earlier, int points, FineGridIntegral& g) {
  const int n = prior.dimension();
  const Eigen::Index size = power(points, n);
  g.spacing = 2.0 * g.box.half_widths / (points - 1);
  const double cell = g.spacing.prod();
  g.nodes.resize(n, size);
  g.weights.resize(size);
  g.log_density = Eigen::VectorXd::Constant(size, -kInf);
  Eigen::VectorXd border = Eigen::VectorXd::Zero(size);
  std::vector<Eigen::Index> live;
  Eigen::VectorXd s(n);
  for (Eigen::Index j = 0; j < size; ++j) {
    Eigen::Index rest = j;
    double w = cell;
    for (int a = 0; a < n; ++a, rest /= points) {
      const Eigen::Index k = rest % points;
      s[a] = -g.box.half_widths[a] + k * g.spacing[a];
      if (k == 0 || k == points - 1) {
        w *= 0.5;
        border[j] = cell;
      }
    }
    g.nodes.col(j) = g.box.centre + g.box.axes * s;
    g.log_density[j] = prior.logDensity(g.nodes.col(j));
    bool counted = std::isfinite(g.log_density[j]);
    for (const FineGridBox& b : earlier) counted = counted && !b.contains(g.nodes.col(j));
    g.weights[j] = counted ? w : 0.0;
    if (counted) {
      live.push_back(j);
    } else {
      g.log_density[j] = -kInf;
    }
  }
  for (std::size_t start = 0; start < live.size(); start += kBatch) {
    const std::size_t end = std::min(live.size(), start + static_cast<std::size_t>(kBatch));
    Eigen::MatrixXd xi(n, static_cast<Eigen::Index>(end - start));
    for (std::size_t i = start; i < end; ++i) xi.col(i - start) = g.nodes.col(live[i]);
    const Eigen::VectorXd ll = logLikelihood(residual.residuals(xi));
    for (std::size_t i = start; i < end; ++i) g.log_density[live[i]] += ll[i - start];
  }
  g.log_mass = logSumExp(g.log_density, g.weights);
  g.peak_log_density = -kInf;
  for (Eigen::Index j = 0; j < size; ++j) {
    if (g.weights[j] > 0.0) g.peak_log_density = std::max(g.peak_log_density, g.log_density[j]);
  }
  const double log_border = logSumExp(g.log_density, border.cwiseProduct(g.weights.cwiseSign()));
  g.border_fraction = std::isfinite(g.log_mass) ? std::exp(log_border - g.log_mass) : 0.0;
}

}  // namespace

bool FineGridBox::contains(const Eigen::Ref<const Eigen::VectorXd>& xi) const {
  const Eigen::VectorXd s = axes.transpose() * (xi - centre);
  for (Eigen::Index i = 0; i < s.size(); ++i) {
    if (std::abs(s[i]) > half_widths[i] * (1.0 + 1e-12)) return false;
  }
  return true;
}

FineGridIntegral integrateMode(const PosteriorResidual& residual, const PriorDensity& prior,
                               const PosteriorModeEstimate& mode,
                               const std::vector<FineGridBox>& earlier,
                               const FineGridSettings& settings,
                               const PosteriorProgress& progress) {
  if (settings.points < 3) throw std::invalid_argument("integrateMode: need >= 3 fine points");
  const int n = prior.dimension();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(mode.hessian);
  if (eigen.info() != Eigen::Success) throw std::runtime_error("integrateMode: Hessian eigen");
  // The box need never exceed the range's diameter: then it covers it all.
  double cap = 0.0;
  for (int i = 0; i < n; ++i) cap += std::pow(prior.gridRange(i).width(), 2);
  cap = std::sqrt(cap);
  FineGridIntegral g;
  g.principal_stddev.resize(n);
  for (int i = 0; i < n; ++i) {
    const double l = eigen.eigenvalues()[i];
    g.principal_stddev[i] = l > 0.0 ? 1.0 / std::sqrt(l) : kInf;
  }
  g.box.centre = mode.xi;
  g.box.axes = eigen.eigenvectors();
  double span = settings.span_sigmas;
  for (int e = 0;; ++e) {
    g.box.half_widths = (span * g.principal_stddev).cwiseMin(cap);
    evaluateGrid(residual, prior, earlier, settings.points, g);
    g.enlargements = e;
    if (progress) {
      std::ostringstream s;
      s << "fine grid: span " << span << " sigma, border mass fraction " << g.border_fraction;
      progress(s.str());
    }
    const bool capped = (g.box.half_widths.array() >= cap).all();
    if (g.border_fraction <= settings.border_mass_tolerance || capped ||
        e >= settings.max_enlargements) {
      break;
    }
    span *= settings.growth;
  }
  return g;
}

void posteriorMoments(const std::vector<FineGridIntegral>& grids, Eigen::VectorXd& mean,
                      Eigen::MatrixXd& covariance) {
  if (grids.empty()) throw std::invalid_argument("posteriorMoments: no grids");
  const Eigen::Index n = grids.front().nodes.rows();
  double reference = -kInf;
  for (const auto& g : grids) reference = std::max(reference, g.peak_log_density);
  if (!std::isfinite(reference)) throw std::runtime_error("posteriorMoments: zero posterior mass");
  double total = 0.0;
  mean = Eigen::VectorXd::Zero(n);
  for (const auto& g : grids) {
    const Eigen::VectorXd m =
        g.weights.cwiseProduct((g.log_density.array() - reference).exp().matrix());
    total += m.sum();
    mean += g.nodes * m;
  }
  mean /= total;
  covariance = Eigen::MatrixXd::Zero(n, n);
  for (const auto& g : grids) {
    const Eigen::VectorXd m =
        g.weights.cwiseProduct((g.log_density.array() - reference).exp().matrix());
    const Eigen::MatrixXd centred = g.nodes.colwise() - mean;
    covariance += centred * m.asDiagonal() * centred.transpose();
  }
  covariance /= total;
}

Histogram marginalHistogram(const std::vector<FineGridIntegral>& grids, const PriorDensity& prior,
                            int dimension, int bins) {
  if (grids.empty() || bins < 1) throw std::invalid_argument("marginalHistogram: no grids or bins");
  const int n = prior.dimension();
  double reference = -kInf;
  for (const auto& g : grids) reference = std::max(reference, g.peak_log_density);
  // Sub-points per axis: about 64 per cell in total.
  const int k = std::max(1, static_cast<int>(std::floor(std::pow(64.0, 1.0 / n) + 1e-9)));
  const Eigen::Index subs = power(k, n);
  std::vector<Eigen::VectorXd> masses, offsets;
  double lo = kInf, hi = -kInf, heaviest = 0.0;
  for (const auto& g : grids) {
    masses.push_back(g.weights.cwiseProduct((g.log_density.array() - reference).exp().matrix()));
    heaviest = std::max(heaviest, masses.back().maxCoeff());
  }
  for (std::size_t i = 0; i < grids.size(); ++i) {
    const auto& g = grids[i];
    const Eigen::VectorXd reach = g.box.axes.row(dimension).transpose().cwiseAbs();
    const double foot = 0.5 * reach.dot(g.spacing);
    Eigen::VectorXd off(subs);
    for (Eigen::Index j = 0; j < subs; ++j) {
      Eigen::Index rest = j;
      double o = 0.0;
      for (int a = 0; a < n; ++a, rest /= k) {
        o += g.box.axes(dimension, a) * ((rest % k + 0.5) / k - 0.5) * g.spacing[a];
      }
      off[j] = o;
    }
    offsets.push_back(off);
    for (Eigen::Index j = 0; j < masses[i].size(); ++j) {
      if (masses[i][j] <= kHistogramRangeMass * heaviest) continue;
      lo = std::min(lo, g.nodes(dimension, j) - foot);
      hi = std::max(hi, g.nodes(dimension, j) + foot);
    }
  }
  lo = std::max(lo, prior.support(dimension).lower);
  hi = std::min(hi, prior.support(dimension).upper);
  if (!(lo < hi)) throw std::runtime_error("marginalHistogram: empty range");
  const double width = (hi - lo) / bins;
  Eigen::VectorXd mass = Eigen::VectorXd::Zero(bins);
  for (std::size_t i = 0; i < grids.size(); ++i) {
    for (Eigen::Index j = 0; j < masses[i].size(); ++j) {
      if (!(masses[i][j] > 0.0)) continue;
      const double share = masses[i][j] / static_cast<double>(subs);
      for (Eigen::Index s = 0; s < subs; ++s) {
        const double b = std::floor((grids[i].nodes(dimension, j) + offsets[i][s] - lo) / width);
        if (b >= 0.0 && b < bins) mass[static_cast<Eigen::Index>(b)] += share;
      }
    }
  }
  Histogram h;
  h.edges = Eigen::VectorXd::LinSpaced(bins + 1, lo, hi);
  h.densities = mass / (mass.sum() * width);
  return h;
}

}  // namespace pc_ekf
