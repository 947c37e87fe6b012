#include "pc_ekf/filter/rollover_quantities.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <future>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <tuple>
#include <utility>
#include <vector>

#include "pc_ekf/pc/background_thread.h"
#include "pc_ekf/pc/basis_key.h"
#include "pc_ekf/pc/sparse_grid.h"

namespace pc_ekf {
namespace {

// Rows of the model's values in the full parameter vector: the roll plane's
// (bar_mass, bar_length, unsprung_mass_left/right) or the full car's
// (body_mass, track_width, unsprung_mass_front/rear, each per wheel: two
// wheels an axle).
struct RolloverRows {
  int bar_mass = -1, added_mass = -1, mount_height = -1, body_cg_height = -1,
      added_mass_height = -1, wheel_radius = -1, track = -1, gravity = -1;
  std::vector<int> unsprung;  // every unsprung_mass_*
  double wheels_per_unsprung = 1.0;  // the full car's are per axle's wheel
  // The full vector's rows rolloverValues reads.
  std::vector<int> read() const {
    std::vector<int> r{bar_mass, added_mass,  mount_height, body_cg_height, added_mass_height,
                       wheel_radius, track, gravity};
    r.insert(r.end(), unsprung.begin(), unsprung.end());
    return r;
  }
  bool complete() const {
    return std::min({bar_mass, added_mass, mount_height, body_cg_height, added_mass_height,
                     wheel_radius, track, gravity}) >= 0 &&
           !unsprung.empty();
  }
};

RolloverRows rowsOf(const ParameterMapping& mapping) {
  RolloverRows r;
  const std::vector<std::string>& names = mapping.modelParameterNames();
  for (int i = 0; i < static_cast<int>(names.size()); ++i) {
    const std::string& n = names[i];
    if (n == "bar_mass" || n == "body_mass") r.bar_mass = i;
    if (n == "added_mass") r.added_mass = i;
    if (n == "mount_height") r.mount_height = i;
    if (n == "body_cg_height") r.body_cg_height = i;
    if (n == "added_mass_height") r.added_mass_height = i;
    if (n == "wheel_radius") r.wheel_radius = i;
    if (n == "bar_length") r.track = i;  // the roll plane's track
    if (n == "track_width") {
      r.track = i;  // the full car's, w
      r.wheels_per_unsprung = 2.0;
    }
    if (n == "gravity") r.gravity = i;
    if (n.rfind("unsprung_mass", 0) == 0) r.unsprung.push_back(i);
  }
  return r;
}

// Tensor rules above this many nodes give way to a sparse grid.
constexpr double kMaxTensorNodes = 20000.0;

}  // namespace

const std::vector<std::string>& rolloverQuantityNames() {
  static const std::vector<std::string> names{"cg_height", "static_stability_factor",
                                              "rollover_threshold"};
  return names;
}

bool hasRolloverQuantities(const ParameterMapping& mapping) {
  const RolloverRows r = rowsOf(mapping);
  return r.complete() && mapping.nominalParameters()(r.mount_height) > 0.0;
}

Eigen::MatrixXd rolloverValues(const ParameterMapping& mapping, const Eigen::MatrixXd& full) {
  const RolloverRows r = rowsOf(mapping);
  if (!r.complete()) throw std::invalid_argument("rolloverValues: the model has no heights");
  Eigen::MatrixXd out(3, full.cols());
  for (Eigen::Index q = 0; q < full.cols(); ++q) {
    const auto p = full.col(q);
    const double m = p(r.bar_mass), M = p(r.added_mass);
    double unsprung = 0.0;
    for (int i : r.unsprung) unsprung += p(i);
    unsprung *= r.wheels_per_unsprung;
    const double first_moment = m * p(r.body_cg_height) + M * p(r.added_mass_height);  // S
    const double h = ((m + M) * p(r.mount_height) + first_moment + unsprung * p(r.wheel_radius)) /
                     (m + M + unsprung);
    const double ssf = p(r.track) / (2.0 * h);
    out(0, q) = h;
    out(1, q) = ssf;
    out(2, q) = p(r.gravity) * ssf;
  }
  return out;
}

void projectionRule(const PolynomialBasis& basis, Eigen::MatrixXd* nodes,
                    Eigen::VectorXd* weights) {
  const int n = basis.order() + 4;
  if (std::pow(double(n), basis.dimension()) <= kMaxTensorNodes) {
    basis.tensorGaussRule(n, nodes, weights);
    return;
  }
  std::vector<OrthonormalFamily> families;
  for (int d = 0; d < basis.dimension(); ++d) families.push_back(basis.family(d));
  SparseGridRule rule = smolyakRule(families, basis.order() + 1);
  *nodes = std::move(rule.nodes);
  *weights = std::move(rule.weights);
}

Eigen::MatrixXd projectValues(const PolynomialBasis& basis, const Eigen::MatrixXd& nodes,
                              const Eigen::VectorXd& weights, const Eigen::MatrixXd& values) {
  // Orthonormal basis: c_j = E[f psi_j] = sum_q w_q f(xi_q) psi_j(xi_q).
  const Eigen::MatrixXd psi = basis.evaluate(nodes);  // Q x S
  return values * weights.asDiagonal() * psi;
}

namespace {

// The rule of a basis (nodes and weights): its basis values are evaluated a
// block of nodes at a time where used, not kept (Q x S is megabytes).
struct Rule {
  Eigen::MatrixXd nodes;  // Q x dimension
  Eigen::VectorXd weights;
  // The basis at every node (Q x S), made at the rule's second use: a node
  // projects again every node.derived_every samples, and evaluating the basis
  // at the nodes was most of each projection's time; a single use
  // (estimate_offline's summary) evaluates a block at a time and holds none of it.
  mutable std::atomic<int> uses{0};
  mutable std::once_flag basis_once;
  mutable Eigen::MatrixXd basis_at_nodes;
  const Eigen::MatrixXd* basisAtNodes(const PolynomialBasis& basis) const {
    if (uses.fetch_add(1) < 1) return nullptr;
    std::call_once(basis_once, [&] { basis_at_nodes = basis.evaluate(nodes); });
    return &basis_at_nodes;
  }
};
// One rule per basis content for the process, made once (in the background
// when prepareRolloverRule came first) and shared by every thread.
std::shared_future<std::shared_ptr<const Rule>> ruleOf(const PolynomialBasis& basis) {
  BasisKey key = basisKey(basis);
  static std::mutex mutex;
  static std::vector<std::pair<BasisKey, std::shared_future<std::shared_ptr<const Rule>>>> cache;
  std::lock_guard<std::mutex> lock(mutex);
  for (const auto& [k, v] : cache) {
    if (k == key) return v;
  }
  std::shared_future<std::shared_ptr<const Rule>> made =
      std::async(std::launch::async, [basis] {
        markBackgroundThread();
        auto r = std::make_shared<Rule>();
        projectionRule(basis, &r->nodes, &r->weights);
        return std::shared_ptr<const Rule>(std::move(r));
      }).share();
  if (cache.size() >= 4) cache.erase(cache.begin());
  cache.emplace_back(std::move(key), made);
  return made;
}

}  // namespace

void prepareRolloverRule(const ParameterMapping& mapping, const PolynomialBasis& basis) {
  if (hasRolloverQuantities(mapping)) ruleOf(basis);
}

DerivedExpansions rolloverExpansions(const ParameterMapping& mapping, const PolynomialBasis& basis,
                                     const Eigen::MatrixXd& parameter_coefficients, int threads) {
  DerivedExpansions out;
  if (!hasRolloverQuantities(mapping) || parameter_coefficients.size() == 0 ||
      !parameter_coefficients.allFinite() || parameter_coefficients.cols() != basis.size() ||
      parameter_coefficients.rows() != mapping.count()) {
    return out;
  }
  const std::shared_ptr<const Rule> rule = ruleOf(basis).get();
  // The terms any parameter uses (an affine expansion: the first degree).
  std::vector<Eigen::Index> used;
  for (Eigen::Index j = 0; j < parameter_coefficients.cols(); ++j) {
    if ((parameter_coefficients.col(j).array() != 0.0).any()) used.push_back(j);
  }
  // Only the parameters the quantities read are evaluated at the nodes (the
  // rest stay 0: rolloverValues does not read them): most of the work.
  std::vector<Eigen::Index> read;
  const std::vector<int> rows = rowsOf(mapping).read();
  for (Eigen::Index i = 0; i < mapping.count(); ++i) {
    const std::string& name = mapping.uncertain()[static_cast<std::size_t>(i)].name;
    if (std::any_of(rows.begin(), rows.end(), [&](int row) {
          return mapping.modelParameterNames()[static_cast<std::size_t>(row)] == name;
        })) {
      read.push_back(i);
    }
  }
  const Eigen::MatrixXd c = parameter_coefficients(read, used);
  // c_j = sum_q w_q f(theta(xi_q)) psi_j(xi_q), a block of nodes at a time
  // (its basis values stay small and in cache).
  constexpr Eigen::Index kBlock = 64;
  const Eigen::Index q_all = rule->nodes.rows();
  const Eigen::Index blocks = (q_all + kBlock - 1) / kBlock;
  std::vector<Eigen::MatrixXd> part(static_cast<std::size_t>(blocks));  // 3 x S each
  const Eigen::MatrixXd* at_nodes = rule->basisAtNodes(basis);
  const auto project = [&](Eigen::Index b0, Eigen::Index b1) {
    for (Eigen::Index b = b0; b < b1; ++b) {
      const Eigen::Index q0 = b * kBlock, count = std::min(kBlock, q_all - q0);
      // count x S: each row its node's alone, so the kept rows are the same numbers.
      const Eigen::MatrixXd psi = at_nodes ? Eigen::MatrixXd(at_nodes->middleRows(q0, count))
                                           : basis.evaluate(rule->nodes.middleRows(q0, count));
      Eigen::MatrixXd theta = Eigen::MatrixXd::Zero(mapping.count(), count);
      theta(read, Eigen::all) = c * psi(Eigen::all, used).transpose();
      const Eigen::MatrixXd values = rolloverValues(mapping, mapping.fullParameters(theta));
      if (!values.allFinite()) return false;
      part[static_cast<std::size_t>(b)].noalias() =
          values * rule->weights.segment(q0, count).asDiagonal() * psi;
    }
    return true;
  };
  bool finite = true;
  if (threads > 1 && blocks >= 4) {
    std::future<bool> later = std::async(std::launch::async, project, blocks / 2, blocks);
    finite = project(0, blocks / 2);
    finite = later.get() && finite;
  } else {
    finite = project(0, blocks);
  }
  if (!finite) return out;
  Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(3, basis.size());
  for (const Eigen::MatrixXd& p : part) sum += p;
  out.names = rolloverQuantityNames();
  out.coefficients = std::move(sum);
  return out;
}

}  // namespace pc_ekf
