#include "pc_ekf/sensitivity/prior_sensitivity.h"

#include <algorithm>
#include <cstdio>
#include <numeric>
#include <stdexcept>

#include "pc_ekf/pc/sobol_indices.h"

namespace pc_ekf {

std::vector<int> PriorSensitivity::ranking() const {
  std::vector<int> order(parameters.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return largestTotal(a) > largestTotal(b); });
  return order;
}

PriorSensitivity priorSensitivity(const PcPropagator& propagator, const std::vector<double>& times,
                                  const std::vector<int>& channels) {
  const MechanicalModel& model = propagator.model();
  const int states = propagator.stateCount();
  const int n = propagator.parameterCount();
  Eigen::MatrixXd h(channels.size(), states);
  PriorSensitivity s;
  s.parameters = propagator.mapping().names();
  for (std::size_t c = 0; c < channels.size(); ++c) {
    h.row(c) = model.observationMatrix().row(channels[c]);
    s.channels.push_back(model.channelNames()[channels[c]]);
  }
  s.total.setZero(n, h.rows());
  s.first.setZero(n, h.rows());
  s.variance.setZero(h.rows());
  Eigen::MatrixXd x = propagator.priorState();
  double t = 0.0;
  Eigen::MatrixXd first, total;
  Eigen::VectorXd variance;
  Eigen::VectorXd missed = Eigen::VectorXd::Zero(h.rows());
  bool loo_everywhere = !times.empty();
  for (double tk : times) {
    const ForecastReport report = propagator.forecast(x, t, tk);
    if (!report.ok) {
      throw std::runtime_error("sensitivity: the prior forecast failed at t = " + std::to_string(tk) +
                               " (" + report.first_problem + ")");
    }
    t = tk;
    sobolPartialVariances(propagator.basis(), h * x.topRows(states), &first, &total, &variance);
    s.first += first;
    s.total += total;
    s.variance += variance;
    // The leave-one-out error covers the leading channels the model gives.
    const bool covered = std::all_of(channels.begin(), channels.end(),
                                     [&](int ch) { return ch < report.loo_error.size(); });
    if (covered) {
      for (Eigen::Index c = 0; c < h.rows(); ++c) {
        missed[c] += report.loo_error[channels[c]] * report.loo_error[channels[c]] * variance[c];
      }
    } else {
      loo_everywhere = false;
    }
  }
  if (loo_everywhere) {
    s.unexplained = Eigen::VectorXd::Zero(h.rows());
    for (Eigen::Index c = 0; c < h.rows(); ++c) {
      if (s.variance[c] > 0) s.unexplained[c] = std::min(1.0, missed[c] / s.variance[c]);
    }
  }
  for (Eigen::Index c = 0; c < h.rows(); ++c) {
    if (s.variance[c] > 0) {
      s.first.col(c) /= s.variance[c];
      s.total.col(c) /= s.variance[c];
    }
  }
  return s;
}

std::string sensitivityTable(const PriorSensitivity& s) {
  std::string out = "total Sobol indices of the prior's readings over the record (ranked)\n";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "  %-24s %8s", "parameter", "largest");
  out += buf;
  for (const auto& c : s.channels) {
    std::snprintf(buf, sizeof(buf), " %8s", c.c_str());
    out += buf;
  }
  out += "\n";
  for (int i : s.ranking()) {
    std::snprintf(buf, sizeof(buf), "  %-24s %8.2e", s.parameters[i].c_str(), s.largestTotal(i));
    out += buf;
    for (Eigen::Index c = 0; c < s.total.cols(); ++c) {
      std::snprintf(buf, sizeof(buf), " %8.2e", s.total(i, c));
      out += buf;
    }
    out += "\n";
  }
  if (s.unexplained.size() > 0) {
    std::snprintf(buf, sizeof(buf), "  %-24s %8s", "missed by the expansion", "");
    out += buf;
    for (Eigen::Index c = 0; c < s.unexplained.size(); ++c) {
      std::snprintf(buf, sizeof(buf), " %8.2e", s.unexplained[c]);
      out += buf;
    }
    out += "   (leave-one-out share of each channel's variance)\n";
  }
  if (!s.expansion.empty()) {
    out += "  expansion: " + s.expansion + " (" + std::to_string(s.simulations) + " simulations)\n";
  }
  return out;
}

}  // namespace pc_ekf
