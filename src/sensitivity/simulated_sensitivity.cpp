#include "pc_ekf/sensitivity/simulated_sensitivity.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>

#include "pc_ekf/filter/posterior_residual.h"
#include "pc_ekf/pc/point_sets.h"
#include "pc_ekf/pc/polynomial_basis.h"
#include "pc_ekf/pc/scrambled_halton.h"
#include "pc_ekf/pc/sobol_indices.h"

namespace pc_ekf {
namespace {

// One least-squares fit of the readings (outputs x Q, output o = channel
// o / T at sample o % T) on `basis` at the first Q points.
struct Fit {
  std::vector<std::vector<int>> indices;
  std::string label;
  Eigen::MatrixXd total, first;  // parameters x channels, normalised
  Eigen::VectorXd variance, missed;
  double worst_missed = std::numeric_limits<double>::infinity();
  int points = 0;
};

Fit fitReadings(const std::vector<GermSpec>& germs, std::vector<std::vector<int>> indices,
                const Eigen::MatrixXd& points, const Eigen::MatrixXd& readings, int channels,
                int samples) {
  Fit f;
  f.indices = indices;
  const PolynomialBasis basis(germs, std::move(indices));
  const Eigen::Index q = points.rows(), s = basis.size();
  f.points = static_cast<int>(q);
  const Eigen::MatrixXd a = basis.evaluate(points);
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(a);
  const Eigen::MatrixXd r = qr.matrixQR().topRows(s).triangularView<Eigen::Upper>();
  const Eigen::ArrayXd diag = r.diagonal().array().abs();
  if (!(diag.minCoeff() > 1e-8 * diag.maxCoeff())) return f;  // rank-deficient: not a candidate
  const Eigen::MatrixXd thin = qr.householderQ() * Eigen::MatrixXd::Identity(q, s);
  const Eigen::MatrixXd coefficients =
      r.triangularView<Eigen::Upper>().solve(thin.transpose() * readings.transpose());  // S x outputs
  const Eigen::VectorXd leverage = thin.rowwise().squaredNorm();
  if (leverage.maxCoeff() >= 1.0 - 1e-12) return f;
  const Eigen::ArrayXd loo_scale = 1.0 / (1.0 - leverage.array());
  const Eigen::MatrixXd residuals = readings.transpose() - a * coefficients;  // Q x outputs
  Eigen::MatrixXd first, total;
  Eigen::VectorXd variance;
  sobolPartialVariances(basis, coefficients.transpose(), &first, &total, &variance);
  const int n = basis.dimension();
  f.total.setZero(n, channels);
  f.first.setZero(n, channels);
  f.variance.setZero(channels);
  f.missed.setZero(channels);
  for (Eigen::Index o = 0; o < readings.rows(); ++o) {
    const Eigen::Index c = o / samples;
    f.total.col(c) += total.col(o);
    f.first.col(c) += first.col(o);
    f.variance[c] += variance[o];
    const double spread = (readings.row(o).array() - readings.row(o).mean()).square().sum();
    if (spread > 0) {
      const double loo = (residuals.col(o).array() * loo_scale).square().sum() / spread;
      f.missed[c] += loo * variance[o];
    }
  }
  f.worst_missed = 0.0;
  for (int c = 0; c < channels; ++c) {
    if (!(f.variance[c] > 0)) continue;
    f.total.col(c) /= f.variance[c];
    f.first.col(c) /= f.variance[c];
    f.missed[c] = std::min(1.0, f.missed[c] / f.variance[c]);
    f.worst_missed = std::max(f.worst_missed, f.missed[c]);
  }
  return f;
}

}  // namespace

Eigen::MatrixXd recordReadings(const MechanicalModel& model, const ParameterMapping& mapping,
                               const Eigen::MatrixXd& xi, const std::vector<double>& times,
                               const std::vector<int>& channels,
                               const IntegratorSettings& integration, int threads,
                               long* simulations) {
  const std::vector<Eigen::MatrixXd> out =
      simulateGermChannels(model, mapping, xi, times, integration, threads, simulations);
  const Eigen::Index samples = static_cast<Eigen::Index>(times.size());
  Eigen::MatrixXd y(static_cast<Eigen::Index>(channels.size()) * samples, xi.cols());
  for (Eigen::Index k = 0; k < samples; ++k) {
    for (std::size_t c = 0; c < channels.size(); ++c) {
      y.row(static_cast<Eigen::Index>(c) * samples + k) = out[k].row(channels[c]);
    }
  }
  return y;
}

std::vector<std::vector<int>> leadingGermIndices(int dimension, const std::vector<int>& leading,
                                                 int lead_order, int mixed_order,
                                                 int other_degree) {
  std::vector<bool> lead(dimension, false);
  for (int g : leading) {
    if (g < 0 || g >= dimension) throw std::invalid_argument("leadingGermIndices: germ out of range");
    lead[g] = true;
  }
  std::vector<std::vector<int>> out;
  for (auto& a : totalDegreeMultiIndices(dimension, std::max(lead_order, mixed_order))) {
    int in_lead = 0, other = 0;
    for (int g = 0; g < dimension; ++g) (lead[g] ? in_lead : other) += a[g];
    const bool keep = other == 0 ? in_lead <= lead_order
                                 : other <= other_degree && in_lead + other <= mixed_order;
    if (keep) out.push_back(std::move(a));
  }
  return out;
}

PriorSensitivity simulatedSensitivity(const MechanicalModel& model, const ParameterMapping& mapping,
                                      const std::vector<double>& record_times,
                                      const std::vector<int>& channels,
                                      const IntegratorSettings& integration,
                                      const SimulatedSensitivitySettings& settings) {
  if (record_times.empty()) throw std::invalid_argument("simulatedSensitivity: no sample times");
  std::vector<double> times = record_times;
  const std::size_t cap = static_cast<std::size_t>(std::max(1, settings.max_samples));
  if (times.size() > cap) {
    times.clear();
    for (std::size_t j = 0; j < cap; ++j) times.push_back(record_times[(j + 1) * record_times.size() / cap - 1]);
  }
  const int n = mapping.count();
  const int channel_count = static_cast<int>(channels.size());
  const int samples = static_cast<int>(times.size());
  const std::vector<GermSpec> germs = mapping.germs();
  // The runs' columns are independent: the same readings on any thread count.
  const int threads = settings.threads > 0
                          ? settings.threads
                          : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  // The points and the readings there, extended as larger bases need them
  // (the scrambled sequence is nested: the first Q points never change).
  Eigen::MatrixXd points(0, n), readings(channel_count * samples, 0);
  long simulations = 0;
  const auto extend = [&](int q) {
    if (q <= points.rows()) return;
    const Eigen::Index have = points.rows();
    const Eigen::MatrixXd more = mapToGerms(
        scrambledHaltonPoints(static_cast<int>(q - have), n, settings.seed,
                              static_cast<std::uint64_t>(have) + 1),
        germs);
    const Eigen::MatrixXd block = recordReadings(model, mapping, more.transpose(), times, channels,
                                                 integration, threads, &simulations);
    if (!block.allFinite()) {
      throw std::runtime_error(
          "sensitivity: a simulation of the prior's design points failed (non-finite readings); "
          "check the uncertain parameters' ranges and the integrator");
    }
    points.conservativeResize(q, Eigen::NoChange);
    points.bottomRows(more.rows()) = more;
    readings.conservativeResize(Eigen::NoChange, q);
    readings.rightCols(more.rows()) = block;
  };
  const auto pointsFor = [&](std::size_t terms) {
    return std::max<int>(static_cast<int>(settings.points_per_term * terms), static_cast<int>(terms) + 2);
  };
  const auto fitWith = [&](std::vector<std::vector<int>> indices, const std::string& label) {
    const int q = pointsFor(indices.size());
    extend(q);
    Fit f = fitReadings(germs, std::move(indices), points.topRows(q), readings.leftCols(q),
                        channel_count, samples);
    f.label = label;
    return f;
  };
  Fit best = fitWith(totalDegreeMultiIndices(n, 2), "total degree 2");
  if (!std::isfinite(best.worst_missed)) {
    throw std::runtime_error("sensitivity: the degree-2 fit is rank-deficient");
  }
  // Germs by their largest total index at degree 2.
  std::vector<int> ranked(n);
  for (int g = 0; g < n; ++g) ranked[g] = g;
  const Eigen::VectorXd largest = best.total.rowwise().maxCoeff();
  std::stable_sort(ranked.begin(), ranked.end(),
                   [&](int a, int b) { return largest[a] > largest[b]; });
  int tried = 1;
  std::set<int> counts;
  for (int k : settings.lead_counts) {
    if (k < 1 || !counts.insert(std::min(k, n)).second) continue;
    const std::vector<int> leading(ranked.begin(), ranked.begin() + std::min(k, n));
    for (int p : settings.lead_orders) {
      auto indices = leadingGermIndices(n, leading, p, settings.mixed_order, settings.other_degree);
      if (static_cast<int>(indices.size()) > settings.max_terms) continue;
      std::string label = "degree " + std::to_string(p) + " in";
      for (int g : leading) label += " " + mapping.names()[g];
      if (static_cast<int>(leading.size()) < n) {
        label += ", the others to degree " + std::to_string(settings.other_degree) +
                 " in terms of degree <= " + std::to_string(settings.mixed_order);
      }
      const Fit f = fitWith(std::move(indices), label);
      ++tried;
      if (f.worst_missed < best.worst_missed) best = f;
    }
  }
  PriorSensitivity s;
  s.parameters = mapping.names();
  for (int c : channels) s.channels.push_back(model.channelNames()[c]);
  s.total = best.total;
  s.first = best.first;
  s.variance = best.variance;
  s.unexplained = best.missed;
  s.simulations = simulations;
  char buf[240];
  std::snprintf(buf, sizeof(buf),
                "; %zu terms on %d scrambled Halton points, whole-record runs read at %zu of %zu "
                "samples (%d bases tried, the least leave-one-out error)",
                best.indices.size(), best.points, times.size(), record_times.size(), tried);
  s.expansion = best.label + buf;
  return s;
}

}  // namespace pc_ekf
