// Conditional-Laplace importance sampling: see mcmc_samplers.h.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "pc_ekf/reference/mcmc_samplers.h"

namespace pc_ekf {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = 3.14159265358979323846;

// xi = centre + V a + W b: a on the ridge (the Laplace covariance's k widest
// directions), b across it.
struct Frame {
  Eigen::VectorXd centre;
  Eigen::MatrixXd v, w;
  Eigen::VectorXd point(const Eigen::VectorXd& a, const Eigen::VectorXd& b) const {
    return centre + v * a + w * b;
  }
};

// One ridge point: the conditional mode over b at fixed a, and the Gaussian
// the proposal places there.
struct Node {
  Eigen::VectorXd a, b;
  Linearisation at;
  Eigen::MatrixXd factor;   // lower Cholesky factor of W^T H W (the conditional precision)
  Eigen::MatrixXd slope;    // d b* / d a = -(W^T H W)^-1 W^T H V: the mode follows a curve
  double log_mass = -kInf;  // -F - 1/2 log det(W^T H W): the Laplace marginal of a
  double lambda = 1e-3;
  bool active = false;
};

Linearisation infeasible(const Eigen::VectorXd& x) {
  Linearisation l;
  l.x = x;
  return l;  // f = +inf
}

// Linearises the points inside the support; the others stay infeasible
// without a simulation.
std::vector<Linearisation> lineariseInside(const PosteriorResidual& residual,
                                           const PriorDensity& prior,
                                           const std::vector<Eigen::VectorXd>& points,
                                           double relative) {
  std::vector<Linearisation> out(points.size());
  std::vector<Eigen::VectorXd> inside;
  std::vector<std::size_t> where;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (std::isfinite(prior.logDensity(points[i]))) {
      inside.push_back(points[i]);
      where.push_back(i);
    } else {
      out[i] = infeasible(points[i]);
    }
  }
  const std::vector<Linearisation> done = linearise(residual, prior, inside, relative);
  for (std::size_t i = 0; i < where.size(); ++i) out[where[i]] = done[i];
  return out;
}

void finishNode(const PriorDensity& prior, const Frame& f, Node& node) {
  if (!std::isfinite(node.at.f)) return;
  const Eigen::MatrixXd h = gaussNewtonHessian(prior, node.at, nullptr);
  const Eigen::MatrixXd hb = f.w.transpose() * h * f.w;
  Eigen::LLT<Eigen::MatrixXd> llt(hb);
  if (llt.info() != Eigen::Success) return;  // not a maximum across the ridge
  node.factor = llt.matrixL();
  node.slope = -llt.solve(f.w.transpose() * h * f.v);
  node.log_mass = -node.at.f - node.factor.diagonal().array().log().sum();
  node.b = f.w.transpose() * (node.at.x - f.centre);
}

// Levenberg-Marquardt on F = 1/2 |r|^2 - log prior over b with a fixed, all
// nodes in one residual batch per iteration; node.b is the start.
void solveConditional(const PosteriorResidual& residual, const PriorDensity& prior, const Frame& f,
                      const std::vector<Node*>& nodes, const ModeSearchSettings& s) {
  std::vector<Eigen::VectorXd> starts;
  for (Node* node : nodes) starts.push_back(f.point(node->a, node->b));
  std::vector<Linearisation> first = lineariseInside(residual, prior, starts, s.difference_step);
  // A start outside the support (a neighbour's mode carried too far): halfway
  // back towards the frame's centre across the ridge, a few times.
  for (int attempt = 0; attempt < 6; ++attempt) {
    std::vector<std::size_t> again;
    std::vector<Eigen::VectorXd> retry;
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      if (std::isfinite(first[i].f)) continue;
      nodes[i]->b *= attempt < 5 ? 0.5 : 0.0;
      again.push_back(i);
      retry.push_back(f.point(nodes[i]->a, nodes[i]->b));
    }
    if (again.empty()) break;
    const auto l = lineariseInside(residual, prior, retry, s.difference_step);
    for (std::size_t j = 0; j < again.size(); ++j) first[again[j]] = l[j];
  }
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    nodes[i]->at = first[i];
    nodes[i]->active = std::isfinite(first[i].f) && f.w.cols() > 0;  // else nothing to solve
    nodes[i]->lambda = 1e-3;
  }
  for (int iteration = 0; iteration < s.max_iterations; ++iteration) {
    std::vector<Node*> trying;
    std::vector<Eigen::VectorXd> trials;
    for (Node* node : nodes) {
      if (!node->active) continue;
      Eigen::VectorXd g;
      const Eigen::MatrixXd h = gaussNewtonHessian(prior, node->at, &g);
      Eigen::MatrixXd hb = f.w.transpose() * h * f.w;
      const double floor = 1e-30 + 1e-15 * hb.diagonal().maxCoeff();
      hb.diagonal() += node->lambda * hb.diagonal().cwiseMax(floor);
      const Eigen::VectorXd step = hb.ldlt().solve(-(f.w.transpose() * g));
      if (!step.allFinite()) {
        node->active = false;
        continue;
      }
      trying.push_back(node);
      trials.push_back(node->at.x + f.w * step);
    }
    if (trying.empty()) break;
    const auto trial = lineariseInside(residual, prior, trials, s.difference_step);
    for (std::size_t t = 0; t < trying.size(); ++t) {
      Node& node = *trying[t];
      const double f_old = node.at.f;
      if (trial[t].f < f_old) {
        node.at = trial[t];
        node.lambda = std::max(node.lambda / 3.0, 1e-12);
        if (f_old - trial[t].f <= s.relative_decrease * (1.0 + std::abs(trial[t].f))) {
          node.active = false;
        }
      } else {
        node.lambda *= 8.0;
        if (node.lambda > 1e12) node.active = false;
      }
    }
  }
  for (Node* node : nodes) finishNode(prior, f, *node);
}

// Start of a node from a solved neighbour: its mode moved along its slope.
void warmStart(const Node& from, Node& to) { to.b = from.b + from.slope * (to.a - from.a); }

// How far the ridge reaches along ridge axis `axis` in direction `sign`: steps
// of `step` until the Laplace marginal falls `drop` below the best seen, or
// the conditional problem leaves the support. Returns the extent (> 0).
double sweepExtent(const PosteriorResidual& residual, const PriorDensity& prior, const Frame& f,
                   const Node& centre, int axis, double sign, double step, double drop, double best,
                   const ModeSearchSettings& s) {
  Node previous = centre;
  for (int t = 1; t <= 60; ++t) {
    Node next;
    next.a = centre.a;
    next.a[axis] += sign * step * t;
    warmStart(previous, next);
    solveConditional(residual, prior, f, {&next}, s);
    if (!std::isfinite(next.log_mass)) return step * t;
    best = std::max(best, next.log_mass);
    if (next.log_mass < best - drop) return step * t;
    previous = next;
  }
  return step * 60;
}

// log of the defensive mixture (1 - eps) N(0, I) + eps t_nu(0, I) at a whitened
// deviation of squared length d2 in `dim` dimensions.
double logWhitenedDensity(double d2, int dim) {
  constexpr double eps = 0.2, nu = 3.0;
  const double log_gauss = -0.5 * dim * std::log(2.0 * kPi) - 0.5 * d2;
  const double log_t = std::lgamma(0.5 * (nu + dim)) - std::lgamma(0.5 * nu) -
                       0.5 * dim * std::log(nu * kPi) - 0.5 * (nu + dim) * std::log1p(d2 / nu);
  const double a = std::log(1.0 - eps) + log_gauss, b = std::log(eps) + log_t;
  const double m = std::max(a, b);
  return m + std::log(std::exp(a - m) + std::exp(b - m));
}

// A whitened deviation from that mixture.
Eigen::VectorXd drawWhitened(int dim, std::mt19937_64& rng) {
  constexpr double eps = 0.2, nu = 3.0;
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> uniform;
  Eigen::VectorXd z(dim);
  for (int i = 0; i < dim; ++i) z[i] = normal(rng);
  if (uniform(rng) < eps) z /= std::sqrt(std::chi_squared_distribution<double>(nu)(rng) / nu);
  return z;
}

// Systematic resampling of `count` indices by normalised weights.
std::vector<Eigen::Index> resample(const Eigen::VectorXd& w, int count, std::mt19937_64& rng) {
  std::vector<Eigen::Index> out;
  out.reserve(count);
  const double u0 = std::uniform_real_distribution<double>(0.0, 1.0 / count)(rng);
  double cumulative = 0.0;
  Eigen::Index i = 0;
  for (int k = 0; k < count; ++k) {
    const double u = u0 + static_cast<double>(k) / count;
    while (i + 1 < w.size() && cumulative + w[i] < u) cumulative += w[i++];
    out.push_back(i);
  }
  return out;
}

}  // namespace

ImportanceRun runConditionalLaplace(const PosteriorResidual& residual, const PriorDensity& prior,
                                    const PosteriorModeEstimate& mode, const McmcSettings& settings,
                                    std::mt19937_64& rng, const PosteriorProgress& progress) {
  const int n = prior.dimension();
  const ModeSearchSettings& ms = settings.mode_search;

  // (a) The frame: the Laplace covariance's k widest directions span the ridge.
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(mode.hessian.inverse());
  int k = settings.ridge_dimensions;
  if (k < 0) {  // automatic: the directions within 100x the widest one's variance
    const Eigen::VectorXd& ev = eig.eigenvalues();
    k = static_cast<int>((ev.array() >= 0.01 * ev[n - 1]).count());
  }
  k = std::min({k, n, 3});
  Frame f;
  f.centre = mode.xi;
  f.v = eig.eigenvectors().rightCols(k);
  f.w = eig.eigenvectors().leftCols(n - k);
  const Eigen::VectorXd widths = eig.eigenvalues().tail(k).cwiseMax(0.0).cwiseSqrt();

  Node centre;
  centre.a = Eigen::VectorXd::Zero(k);
  centre.b = Eigen::VectorXd::Zero(n - k);
  solveConditional(residual, prior, f, {&centre}, ms);
  if (!std::isfinite(centre.log_mass)) {
    throw std::runtime_error("runMcmcReference: the conditional Laplace fails at the mode");
  }

  // (b) The grid's reach along each ridge axis, both ways.
  Eigen::VectorXd lower(k), upper(k);
  for (int j = 0; j < k; ++j) {
    const double step = 0.5 * std::max(widths[j], 1e-6);
    lower[j] = -sweepExtent(residual, prior, f, centre, j, -1.0, step, settings.grid_drop,
                            centre.log_mass, ms);
    upper[j] = sweepExtent(residual, prior, f, centre, j, 1.0, step, settings.grid_drop,
                           centre.log_mass, ms);
  }
  if (progress) progress("conditional Laplace: ridge axes swept");

  // (c) The grid, solved in waves outward from the node nearest the mode, each
  // node started from a solved neighbour of the previous wave.
  const int m = settings.grid_points > 0 ? settings.grid_points : (k <= 1 ? 41 : k == 2 ? 21 : 15);
  const Eigen::VectorXd spacing = (upper - lower) / (m - 1);
  std::vector<Node> nodes;
  std::vector<int> index(k);
  std::vector<int> origin(k);
  for (int j = 0; j < k; ++j) {
    origin[j] = static_cast<int>(std::lround(-lower[j] / spacing[j]));
  }
  long total = 1;
  for (int j = 0; j < k; ++j) total *= m;
  nodes.resize(total);
  std::vector<int> wave(total);
  auto unpack = [&](long id, std::vector<int>& idx) {
    for (int j = 0; j < k; ++j) {
      idx[j] = static_cast<int>(id % m);
      id /= m;
    }
  };
  int waves = 0;
  for (long id = 0; id < total; ++id) {
    unpack(id, index);
    Node& node = nodes[id];
    node.a.resize(k);
    int distance = 0;
    for (int j = 0; j < k; ++j) {
      node.a[j] = lower[j] + spacing[j] * index[j];
      distance = std::max(distance, std::abs(index[j] - origin[j]));
    }
    wave[id] = distance;
    waves = std::max(waves, distance);
  }
  std::vector<int> neighbour(k);
  for (int d = 0; d <= waves; ++d) {
    std::vector<Node*> batch;
    for (long id = 0; id < total; ++id) {
      if (wave[id] != d) continue;
      Node& node = nodes[id];
      if (d == 0) {
        warmStart(centre, node);
      } else {
        // The best solved neighbour one wave in.
        unpack(id, index);
        const Node* from = nullptr;
        for (long other = 0; other < total; ++other) {
          if (wave[other] != d - 1 || !std::isfinite(nodes[other].log_mass)) continue;
          unpack(other, neighbour);
          bool adjacent = true;
          for (int j = 0; j < k; ++j) adjacent = adjacent && std::abs(neighbour[j] - index[j]) <= 1;
          if (adjacent && (from == nullptr || nodes[other].log_mass > from->log_mass)) {
            from = &nodes[other];
          }
        }
        if (from == nullptr) continue;  // beyond the ridge's reach: no mass
        warmStart(*from, node);
      }
      batch.push_back(&node);
    }
    solveConditional(residual, prior, f, batch, ms);
    if (progress) {
      progress("conditional Laplace: grid wave " + std::to_string(d) + "/" + std::to_string(waves));
    }
  }

  // (d) The proposal: a node by its Laplace mass, a uniformly within its cell,
  // b around the node's mode carried along its slope, with the conditional
  // covariance and a heavy-tailed share.
  std::vector<const Node*> live;
  Eigen::VectorXd log_mass;
  {
    std::vector<double> lm;
    for (const Node& node : nodes) {
      if (std::isfinite(node.log_mass)) {
        live.push_back(&node);
        lm.push_back(node.log_mass);
      }
    }
    log_mass = Eigen::Map<Eigen::VectorXd>(lm.data(), static_cast<Eigen::Index>(lm.size()));
  }
  const Eigen::VectorXd cell_weight = (log_mass.array() - log_mass.maxCoeff()).exp();
  std::discrete_distribution<std::size_t> pick(cell_weight.data(),
                                               cell_weight.data() + cell_weight.size());
  const double log_cell_volume = spacing.array().log().sum();
  const double log_total = std::log(cell_weight.sum());
  std::vector<double> log_det(live.size());  // log det of the conditional covariance
  for (std::size_t i = 0; i < live.size(); ++i) {
    log_det[i] = -2.0 * live[i]->factor.diagonal().array().log().sum();
  }

  // (e) Batches of independent draws, weighted by posterior / proposal.
  ImportanceRun out;
  out.nodes = static_cast<int>(live.size());
  out.ridge_dimensions = k;
  const int batches = settings.chains, draws = settings.samples;
  Eigen::MatrixXd xi(n, static_cast<Eigen::Index>(batches) * draws);
  Eigen::VectorXd log_q(xi.cols());
  std::uniform_real_distribution<double> uniform(-0.5, 0.5);
  for (Eigen::Index c = 0; c < xi.cols(); ++c) {
    const std::size_t i = pick(rng);
    const Node& node = *live[i];
    Eigen::VectorXd a = node.a;
    for (int j = 0; j < k; ++j) a[j] += spacing[j] * uniform(rng);
    const Eigen::VectorXd z = drawWhitened(n - k, rng);
    // b = mu + L^-T z: covariance (L L^T)^-1.
    const Eigen::VectorXd mu = node.b + node.slope * (a - node.a);
    const Eigen::VectorXd b = mu + node.factor.transpose().triangularView<Eigen::Upper>().solve(z);
    xi.col(c) = f.point(a, b);
    log_q[c] = std::log(cell_weight[i]) - log_total - log_cell_volume +
               logWhitenedDensity(z.squaredNorm(), n - k) - 0.5 * log_det[i];
  }
  Eigen::VectorXd log_w(xi.cols());
  constexpr Eigen::Index kChunk = 4096;
  for (Eigen::Index c = 0; c < xi.cols(); c += kChunk) {
    const Eigen::Index len = std::min(kChunk, xi.cols() - c);
    log_w.segment(c, len) = logPosterior(residual, prior, xi.middleCols(c, len));
    if (progress) {
      progress("conditional Laplace: " + std::to_string(c + len) + "/" + std::to_string(xi.cols()) +
               " draws");
    }
  }
  log_w -= log_q;
  const double top = log_w.maxCoeff();
  Eigen::VectorXd w = (log_w.array() - top).exp().matrix();
  for (Eigen::Index c = 0; c < w.size(); ++c) {
    if (!std::isfinite(w[c])) w[c] = 0.0;
  }
  w /= w.sum();

  // (f) Weighted moments; per parameter the importance ESS of its mean
  // (variance / sum w^2 (x - mean)^2); R-hat over the batches, each resampled.
  out.mean = xi * w;
  const Eigen::MatrixXd centred = xi.colwise() - out.mean;
  out.covariance = centred * w.asDiagonal() * centred.transpose();
  out.effective_size.resize(n);
  for (int p = 0; p < n; ++p) {
    const double spread =
        (w.array() * w.array() * centred.row(p).transpose().array().square()).sum();
    out.effective_size[p] = spread > 0.0 ? out.covariance(p, p) / spread : 0.0;
  }
  out.kish = 1.0 / w.squaredNorm();
  out.efficiency = out.kish / static_cast<double>(w.size());
  out.largest_weight = w.maxCoeff();
  const int kept = std::max(8, draws / settings.thin);
  out.draws.assign(batches, Eigen::MatrixXd(n, kept));
  for (int bt = 0; bt < batches; ++bt) {
    Eigen::VectorXd wb = w.segment(static_cast<Eigen::Index>(bt) * draws, draws);
    const double sum = wb.sum();
    if (!(sum > 0.0)) {
      out.draws[bt].setConstant(std::numeric_limits<double>::quiet_NaN());
      continue;
    }
    wb /= sum;
    const auto pickd = resample(wb, kept, rng);
    std::vector<Eigen::Index> order(pickd.begin(), pickd.end());
    std::shuffle(order.begin(), order.end(), rng);  // split R-hat compares halves
    for (int j = 0; j < kept; ++j) {
      out.draws[bt].col(j) = xi.col(static_cast<Eigen::Index>(bt) * draws + order[j]);
    }
  }
  out.r_hat.resize(n);
  for (int p = 0; p < n; ++p) {
    Eigen::MatrixXd one(batches, kept);
    for (int bt = 0; bt < batches; ++bt) one.row(bt) = out.draws[bt].row(p);
    out.r_hat[p] = one.allFinite() ? splitRHat(one) : kInf;
  }
  return out;
}

}  // namespace pc_ekf
