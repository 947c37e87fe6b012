#include "pc_ekf/reference/posterior_mode_search.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace pc_ekf {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Steps point into the support so that no stencil point leaves it.
Eigen::VectorXd differenceSteps(const PriorDensity& prior, const Eigen::VectorXd& x,
                                double relative) {
  Eigen::VectorXd h(x.size());
  for (int i = 0; i < x.size(); ++i) {
    h[i] = relative * prior.gridRange(i).width();
    if (x[i] + h[i] > prior.support(i).upper) h[i] = -h[i];
  }
  return h;
}

struct Search {
  Linearisation at;
  Eigen::MatrixXd hessian;  // Gauss-Newton, at `at`
  int duplicate_of = -1;
  double lambda = 1e-3;
  bool active = true;
  bool converged = false;
  int iterations = 0;
};

// Many coarse maxima lie in one basin (a narrow ridge sampled by a coarse
// grid): a search within merge_distance Gauss-Newton std of a better one
// would only converge to the same mode, so it stops there.
void mergeDuplicates(std::vector<Search>& searches, double merge_distance) {
  for (std::size_t s = 0; s < searches.size(); ++s) {
    if (!searches[s].active) continue;
    for (std::size_t t = 0; t < searches.size(); ++t) {
      const Search& other = searches[t];
      const bool better =
          other.at.f < searches[s].at.f || (other.at.f == searches[s].at.f && t < s);
      if (t == s || other.duplicate_of >= 0 || !better) continue;
      const Eigen::VectorXd d = searches[s].at.x - other.at.x;
      if (d.dot(other.hessian * d) < merge_distance * merge_distance) {
        searches[s].active = false;
        searches[s].duplicate_of = static_cast<int>(t);
        break;
      }
    }
  }
}

}  // namespace

std::vector<Linearisation> linearise(const PosteriorResidual& residual, const PriorDensity& prior,
                                     const std::vector<Eigen::VectorXd>& points, double relative) {
  const int n = prior.dimension();
  const Eigen::Index stride = n + 1;
  Eigen::MatrixXd xi(n, stride * static_cast<Eigen::Index>(points.size()));
  std::vector<Eigen::VectorXd> steps;
  for (std::size_t p = 0; p < points.size(); ++p) {
    steps.push_back(differenceSteps(prior, points[p], relative));
    for (int i = 0; i <= n; ++i) {
      xi.col(p * stride + i) = points[p];
      if (i > 0) xi(i - 1, p * stride + i) += steps[p][i - 1];
    }
  }
  const Eigen::MatrixXd r = points.empty() ? Eigen::MatrixXd() : residual.residuals(xi);
  std::vector<Linearisation> out(points.size());
  for (std::size_t p = 0; p < points.size(); ++p) {
    Linearisation& l = out[p];
    l.x = points[p];
    l.r = r.col(p * stride);
    l.jacobian = Eigen::MatrixXd::Zero(r.rows(), n);
    const double log_prior = prior.logDensity(l.x);
    if (!l.r.allFinite() || !std::isfinite(log_prior)) continue;  // f stays +inf
    l.f = 0.5 * l.r.squaredNorm() - log_prior;
    for (int i = 0; i < n; ++i) {
      const auto shifted = r.col(p * stride + 1 + i);
      // A non-finite neighbour (inadmissible parameters) leaves that column 0:
      // the prior and the damping still give a usable step.
      if (shifted.allFinite()) l.jacobian.col(i) = (shifted - l.r) / steps[p][i];
    }
  }
  return out;
}

Eigen::MatrixXd gaussNewtonHessian(const PriorDensity& prior, const Linearisation& l,
                                   Eigen::VectorXd* gradient) {
  Eigen::VectorXd prior_gradient, curvature;
  prior.derivatives(l.x, prior_gradient, curvature);
  Eigen::MatrixXd h = l.jacobian.transpose() * l.jacobian;
  h.diagonal() += curvature;
  if (gradient != nullptr) *gradient = l.jacobian.transpose() * l.r - prior_gradient;
  return h;
}

std::vector<PosteriorModeEstimate> refineModes(const PosteriorResidual& residual,
                                               const PriorDensity& prior,
                                               const std::vector<Eigen::VectorXd>& starts,
                                               const ModeSearchSettings& settings) {
  if (residual.dimension() != prior.dimension()) {
    throw std::invalid_argument("refineModes: residual and prior dimensions differ");
  }
  std::vector<Search> searches(starts.size());
  {
    const auto initial = linearise(residual, prior, starts, settings.difference_step);
    for (std::size_t s = 0; s < starts.size(); ++s) {
      searches[s].at = initial[s];
      searches[s].hessian = gaussNewtonHessian(prior, initial[s], nullptr);
      if (!std::isfinite(initial[s].f)) {
        throw std::invalid_argument("refineModes: a start has zero posterior density");
      }
    }
    mergeDuplicates(searches, settings.merge_distance);
  }
  for (int iteration = 0; iteration < settings.max_iterations; ++iteration) {
    std::vector<std::size_t> trying;
    std::vector<Eigen::VectorXd> trials;
    for (std::size_t s = 0; s < searches.size(); ++s) {
      Search& search = searches[s];
      if (!search.active) continue;
      Eigen::VectorXd g;
      const Eigen::MatrixXd h = gaussNewtonHessian(prior, search.at, &g);
      // Marquardt's scaling: damping proportional to the diagonal.
      Eigen::MatrixXd damped = h;
      const double floor = 1e-30 + 1e-15 * h.diagonal().maxCoeff();
      damped.diagonal() += search.lambda * h.diagonal().cwiseMax(floor);
      const Eigen::VectorXd step = damped.ldlt().solve(-g);
      if (!step.allFinite()) {
        search.active = false;
        continue;
      }
      trying.push_back(s);
      trials.push_back(prior.clamp(search.at.x + step));
    }
    if (trying.empty()) break;
    const auto trial = linearise(residual, prior, trials, settings.difference_step);
    for (std::size_t t = 0; t < trying.size(); ++t) {
      Search& search = searches[trying[t]];
      ++search.iterations;
      const double f_old = search.at.f;
      if (trial[t].f < f_old) {
        search.at = trial[t];
        search.hessian = gaussNewtonHessian(prior, search.at, nullptr);
        search.lambda = std::max(search.lambda / 3.0, 1e-12);
        if (f_old - trial[t].f <= settings.relative_decrease * (1.0 + std::abs(trial[t].f))) {
          search.converged = true;
          search.active = false;
        }
      } else {
        search.lambda *= 8.0;
        // No decrease even for a tiny damped step: at the minimum to round-off.
        if (search.lambda > 1e12) {
          search.converged = true;
          search.active = false;
        }
      }
    }
    mergeDuplicates(searches, settings.merge_distance);
  }
  std::vector<PosteriorModeEstimate> out;
  for (const Search& search : searches) {
    PosteriorModeEstimate m;
    m.xi = search.at.x;
    m.log_density = -search.at.f;
    m.hessian = gaussNewtonHessian(prior, search.at, nullptr);
    m.iterations = search.iterations;
    m.converged = search.converged;
    m.duplicate_of = search.duplicate_of;
    out.push_back(m);
  }
  return out;
}

}  // namespace pc_ekf
