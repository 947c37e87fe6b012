#include "pc_ekf/ros/message_conversion.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "pc_ekf/filter/pc_propagator.h"
#include "pc_ekf/io/estimator_config.h"
#include "pc_ekf/pc/germ.h"

namespace pc_ekf {

namespace {

constexpr std::int64_t kNanosecondsPerSecond = 1000000000LL;

std::int64_t nanoseconds(const ros::Time& t) {
  return static_cast<std::int64_t>(t.sec) * kNanosecondsPerSecond + t.nsec;
}

ros::Time timeFromNanoseconds(std::int64_t ns, const char* what) {
  constexpr std::int64_t kMax = (static_cast<std::int64_t>(1) << 32) * kNanosecondsPerSecond;
  if (ns < 0 || ns >= kMax) {
    throw std::invalid_argument(std::string(what) + ": time outside ros::Time's range [0, 2^32) s");
  }
  ros::Time t;
  t.sec = static_cast<std::uint32_t>(ns / kNanosecondsPerSecond);
  t.nsec = static_cast<std::uint32_t>(ns % kNanosecondsPerSecond);
  return t;
}

std::vector<double> toStd(const Eigen::VectorXd& v) { return {v.data(), v.data() + v.size()}; }

std::string coherenceWarning(const ParameterEstimate& msg) {
  std::ostringstream w;
  w << "multi-rate coherence check: full and decimated (1 in " << msg.coherence_decimation
    << ") streams disagree by more than " << msg.coherence_threshold
    << " combined standard deviations";
  return w.str();
}

}  // namespace

double secondsSince(const ros::Time& stamp, const ros::Time& origin) {
  // Division (not multiplication by 1e-9) rounds correctly: 300000000 ns -> 0.3.
  return static_cast<double>(nanoseconds(stamp) - nanoseconds(origin)) /
         static_cast<double>(kNanosecondsPerSecond);
}

ros::Time stampAt(const ros::Time& origin, double t) {
  if (!std::isfinite(t) || std::abs(t) > 5e9) {
    throw std::invalid_argument("stampAt: time offset not finite or beyond ros::Time's range");
  }
  return timeFromNanoseconds(nanoseconds(origin) + std::llround(t * 1e9), "stampAt");
}

ros::Time timeFromSeconds(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0.0 || seconds >= 4294967296.0) {
    throw std::invalid_argument("time " + std::to_string(seconds) +
                                " s is not in ros::Time's range [0, 2^32)");
  }
  const double whole = std::floor(seconds);
  std::int64_t ns = static_cast<std::int64_t>(whole) * kNanosecondsPerSecond +
                    std::llround((seconds - whole) * 1e9);
  return timeFromNanoseconds(ns, "timeFromSeconds");
}

// ---------------------------------------------------------------- JointState

JointStateConversion measurementFromJointState(const sensor_msgs::JointState& msg, double time,
                                               const SuspensionJoints& joints) {
  JointStateConversion out;
  out.measurement.time = time;
  const std::size_t n = msg.name.size();
  const bool positions_ok = msg.position.empty() || msg.position.size() == n;
  const bool velocities_ok = msg.velocity.empty() || msg.velocity.size() == n;
  if (!positions_ok) {
    out.problems.push_back("position has " + std::to_string(msg.position.size()) + " entries for " +
                           std::to_string(n) + " joint names; ignored");
    out.problem_kinds.push_back(JointStateProblem::kArrayLength);
  }
  if (!velocities_ok) {
    out.problems.push_back("velocity has " + std::to_string(msg.velocity.size()) + " entries for " +
                           std::to_string(n) + " joint names; ignored");
    out.problem_kinds.push_back(JointStateProblem::kArrayLength);
  }

  // Index of each configured joint in the message; -1 = not in the message.
  const std::vector<SuspensionJoints::Joint> wanted = joints.resolved();
  std::vector<int> index(wanted.size(), -1);
  std::vector<bool> duplicate(wanted.size(), false);
  for (std::size_t i = 0; i < n; ++i) {
    const std::string& name = msg.name[i];
    int side = -1;
    for (std::size_t k = 0; k < wanted.size(); ++k) {
      if (name == wanted[k].name) side = static_cast<int>(k);
    }
    if (side < 0) {
      std::string expected;
      for (std::size_t k = 0; k < wanted.size(); ++k) {
        expected += (k == 0 ? "'" : k + 1 == wanted.size() ? "' or '" : "', '") + wanted[k].name;
      }
      out.problems.push_back("unknown joint name '" + name + "' (expected " + expected + "'); ignored");
      out.problem_kinds.push_back(JointStateProblem::kUnknownJoint);
      continue;
    }
    if (index[side] >= 0) duplicate[side] = true;
    index[side] = static_cast<int>(i);
  }

  const int channels = joints.channelCount();
  std::vector<double> values(channels, 0.0);
  std::vector<bool> observed(channels, false);
  for (std::size_t side = 0; side < wanted.size(); ++side) {
    const std::string& name = wanted[side].name;
    if (duplicate[side]) {
      out.problems.push_back("joint '" + name + "' appears more than once; ignored");
      out.problem_kinds.push_back(JointStateProblem::kDuplicateJoint);
      continue;
    }
    if (index[side] < 0) continue;
    const auto take = [&](const std::vector<double>& array, bool usable, int channel,
                          const char* field) {
      if (!usable || array.empty() || channel < 0) return;
      const double v = array[index[side]];
      if (std::isnan(v)) {  // not observed
        ++out.nan_elements;
        return;
      }
      if (!std::isfinite(v)) {
        out.problems.push_back(std::string(field) + " of '" + name + "' is not finite; ignored");
        out.problem_kinds.push_back(JointStateProblem::kNonFinite);
        return;
      }
      values[channel] = v;
      observed[channel] = true;
    };
    take(msg.position, positions_ok, wanted[side].position, "position");
    take(msg.velocity, velocities_ok, wanted[side].velocity, "velocity");
  }

  std::vector<double> kept;
  for (int c = 0; c < channels; ++c) {
    if (!observed[c]) continue;
    out.measurement.channels.push_back(c);
    kept.push_back(values[c]);
  }
  out.measurement.values = Eigen::Map<const Eigen::VectorXd>(kept.data(), kept.size());
  return out;
}

sensor_msgs::JointState jointStateFromMeasurement(const Measurement& m, const ros::Time& stamp,
                                                  const SuspensionJoints& joints) {
  if (static_cast<Eigen::Index>(m.channels.size()) != m.values.size()) {
    throw std::invalid_argument("jointStateFromMeasurement: " + std::to_string(m.channels.size()) +
                                " channels but " + std::to_string(m.values.size()) + " values");
  }
  const int channels = joints.channelCount();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> values(channels, nan);
  for (std::size_t i = 0; i < m.channels.size(); ++i) {
    const int c = m.channels[i];
    if (c < 0 || c >= channels) {
      throw std::invalid_argument("jointStateFromMeasurement: channel " + std::to_string(c) +
                                  " is not one of the model's " + std::to_string(channels) +
                                  " channels (0.." + std::to_string(channels - 1) + ")");
    }
    values[c] = m.values(static_cast<Eigen::Index>(i));
  }
  sensor_msgs::JointState js;
  js.header.stamp = stamp;
  for (const auto& joint : joints.resolved()) {
    js.name.push_back(joint.name);
    js.position.push_back(joint.position >= 0 ? values[joint.position] : nan);
    js.velocity.push_back(joint.velocity >= 0 ? values[joint.velocity] : nan);
  }
  return js;
}

SuspensionJoints::SuspensionJoints()
    : SuspensionJoints(suspensionJoints(*rollPlaneType(), defaultJointNames(*rollPlaneType()))) {}

SuspensionJoints suspensionJoints(const ModelType& type, const std::vector<std::string>& names) {
  SuspensionJoints out({}, 0);
  const auto& suspensions = type.suspensions();
  if (names.size() != suspensions.size()) {
    throw std::invalid_argument("suspensionJoints: " + std::to_string(names.size()) +
                                " joint names for " + std::to_string(suspensions.size()) +
                                " suspensions");
  }
  for (std::size_t k = 0; k < names.size(); ++k) {
    out.joints.push_back({names[k], suspensions[k].position_channel, suspensions[k].velocity_channel});
  }
  out.channels = static_cast<int>(type.channelNames().size());
  return out;
}

RoadHeights roadHeightsMessage(const ros::Time& stamp, const std::vector<std::string>& contacts,
                               const std::vector<double>& heights) {
  RoadHeights r;
  r.header.stamp = stamp;
  r.contacts = contacts;
  r.heights = heights;
  return r;
}

std::string roadHeightsInOrder(const RoadHeights& msg, const std::vector<std::string>& contacts,
                               std::vector<double>* heights) {
  if (msg.contacts.size() != msg.heights.size()) {
    return std::to_string(msg.contacts.size()) + " contacts but " +
           std::to_string(msg.heights.size()) + " heights";
  }
  heights->assign(contacts.size(), 0.0);
  std::vector<bool> seen(contacts.size(), false);
  for (std::size_t i = 0; i < msg.contacts.size(); ++i) {
    const auto it = std::find(contacts.begin(), contacts.end(), msg.contacts[i]);
    if (it == contacts.end()) return "unknown contact '" + msg.contacts[i] + "'";
    const std::size_t c = static_cast<std::size_t>(it - contacts.begin());
    if (seen[c]) return "contact '" + msg.contacts[i] + "' given twice";
    if (!std::isfinite(msg.heights[i])) return "height of '" + msg.contacts[i] + "' is not finite";
    seen[c] = true;
    (*heights)[c] = msg.heights[i];
  }
  for (std::size_t c = 0; c < contacts.size(); ++c) {
    if (!seen[c]) return "no height for contact '" + contacts[c] + "'";
  }
  return "";
}

RoadProfile roadProfileMessage(const ros::Time& stamp, double left, double right) {
  RoadProfile r;
  r.header.stamp = stamp;
  r.left = left;
  r.right = right;
  return r;
}

// ------------------------------------------------------------------ estimates

void setParameters(ParameterEstimate& msg, const ParameterMapping& mapping,
                   const Eigen::VectorXd& mean, const Eigen::VectorXd& stddev) {
  const int n = mapping.count();
  if (mean.size() != n || stddev.size() != n) {
    throw std::invalid_argument("setParameters: " + std::to_string(mean.size()) + " means and " +
                                std::to_string(stddev.size()) + " stddevs for " +
                                std::to_string(n) + " parameters");
  }
  msg.names = mapping.names();
  msg.mean = toStd(mean);
  msg.stddev = toStd(stddev);
  // The map value = nominal (1 + range xi) is affine: xi of the mean is the
  // germ mean, and the germ stddev is stddev / |nominal range|.
  msg.xi_mean = toStd(mapping.germOf(mean));
  msg.xi_stddev.resize(n);
  for (int i = 0; i < n; ++i) {
    const auto& p = mapping.uncertain()[i];
    const double scale = std::abs(p.nominal * p.relative_range);
    msg.xi_stddev[i] = scale > 0.0 ? stddev(i) / scale : std::numeric_limits<double>::quiet_NaN();
  }
}

void setBasis(ParameterEstimate& msg, const PolynomialBasis& basis) {
  msg.germ_family.clear();
  msg.germ_alpha.clear();
  msg.germ_beta.clear();
  for (const GermSpec& g : basis.germs()) {
    msg.germ_family.push_back(toString(g.family));
    msg.germ_alpha.push_back(g.alpha);
    msg.germ_beta.push_back(g.beta);
  }
  msg.total_degree = static_cast<std::uint32_t>(basis.order());
  msg.multi_indices.clear();
  msg.multi_indices.reserve(basis.size() * basis.dimension());
  for (const auto& index : basis.multiIndices()) {
    for (int e : index) msg.multi_indices.push_back(static_cast<std::uint32_t>(e));
  }
  msg.term_count = static_cast<std::uint32_t>(basis.size());
}

void setCoefficients(ParameterEstimate& msg, const Eigen::MatrixXd& coefficients) {
  msg.coefficients.resize(coefficients.size());
  const Eigen::Index rows = coefficients.rows(), cols = coefficients.cols();
  for (Eigen::Index i = 0; i < rows; ++i) {
    for (Eigen::Index j = 0; j < cols; ++j) msg.coefficients[i * cols + j] = coefficients(i, j);
  }
  if (coefficients.size() > 0) msg.term_count = static_cast<std::uint32_t>(cols);
}

void setDerived(ParameterEstimate& msg, const DerivedExpansions& d) {
  msg.derived_names = d.names;
  if (d.empty()) {
    msg.derived_mean.clear();
    msg.derived_stddev.clear();
    msg.derived_coefficients.clear();
    return;
  }
  msg.derived_mean = toStd(pcMean(d.coefficients));
  msg.derived_stddev = toStd(pcStddev(d.coefficients));
  const Eigen::Index rows = d.coefficients.rows(), cols = d.coefficients.cols();
  msg.derived_coefficients.resize(d.coefficients.size());
  for (Eigen::Index i = 0; i < rows; ++i) {
    for (Eigen::Index j = 0; j < cols; ++j) {
      msg.derived_coefficients[i * cols + j] = d.coefficients(i, j);
    }
  }
}

void setRolloverOutputs(ParameterEstimate& msg, const ParameterMapping& mapping,
                        const PolynomialBasis& basis, const Eigen::MatrixXd& coefficients) {
  setDerived(msg, rolloverExpansions(mapping, basis, coefficients));
  msg.derived_sample_index = msg.derived_names.empty() ? 0 : msg.sample_index;
}

void setRates(ParameterEstimate& msg, const SafeguardRates& r, double window) {
  msg.rate_window = window;
  msg.rate_names.clear();
  msg.rate_window_count.clear();
  msg.rate_window_expected.clear();
  msg.rate_window_tail.clear();
  msg.rate_run_count.clear();
  msg.rate_run_expected.clear();
  msg.rate_run_tail.clear();
  msg.rate_flagged.clear();
  msg.rates_flagged = r.flagged();
  if (!r.available) return;
  const std::pair<const char*, const SafeguardRate*> rates[] = {
      {"gated", &r.gated}, {"damped", &r.damped}, {"reopened", &r.reopened}, {"support", &r.support}};
  for (const auto& [name, rate] : rates) {
    msg.rate_names.push_back(name);
    msg.rate_window_count.push_back(static_cast<std::uint32_t>(rate->window.count));
    msg.rate_window_expected.push_back(rate->window.expected);
    msg.rate_window_tail.push_back(rate->window.tail);
    msg.rate_run_count.push_back(static_cast<std::uint32_t>(rate->run.count));
    msg.rate_run_expected.push_back(rate->run.expected);
    msg.rate_run_tail.push_back(rate->run.tail);
    msg.rate_flagged.push_back(rate->flagged());
  }
}

void setHealth(ParameterEstimate& msg, const HealthStatus& h, int nis_channels,
               const HealthSettings& settings) {
  msg.nis = h.nis;
  msg.nis_channels = static_cast<std::uint32_t>(std::max(0, nis_channels));
  msg.nis_confidence = settings.nis_confidence;
  msg.nis_lower = h.nis_lower;
  msg.nis_upper = h.nis_upper;
  msg.nis_outside = h.nis_outside;
  msg.nis_window = static_cast<std::uint32_t>(std::max(0, settings.nis_window));
  msg.nis_window_mean = h.nis_window_mean;
  msg.nis_window_lower = h.window_lower;
  msg.nis_window_upper = h.window_upper;
  msg.nis_window_outside = h.nis_window_outside;
  msg.mass_outside_support = toStd(h.mass_outside_support);
  msg.support_exceeded = h.support_exceeded;
  msg.non_finite = h.non_finite;
  msg.forecast_failed = h.forecast_failed;
  msg.band_nested = h.band_nested;
  msg.loo_error = toStd(h.loo_error);
  msg.loo_warning = settings.loo_warning;
  msg.loo_exceeded = h.loo_exceeded;
  setRates(msg, h.rates, settings.rate_window);
  msg.healthy = h.healthy() && !msg.coherence_flagged;
  msg.warnings = h.warnings();
  if (msg.coherence_flagged) msg.warnings.push_back(coherenceWarning(msg));
}

void setPredictiveCheck(ParameterEstimate& msg, const PredictiveCheck& p,
                        const std::string& warning) {
  msg.predictive_available = p.available;
  msg.predictive_statistic = p.statistic;
  msg.predictive_dof = static_cast<std::uint32_t>(std::max(0, p.dof));
  msg.predictive_lower = p.lower;
  msg.predictive_upper = p.upper;
  msg.predictive_outside = p.outside;
  if (p.outside) {
    msg.healthy = false;
    msg.warnings.push_back(warning);
  }
}

void setCoherence(ParameterEstimate& msg, const Eigen::VectorXd& disagreement, int decimation,
                  double threshold) {
  msg.coherence_disagreement = toStd(disagreement);
  msg.coherence_decimation = static_cast<std::uint32_t>(std::max(0, decimation));
  msg.coherence_threshold = threshold;
  // NaN disagreement counts as flagged.
  msg.coherence_flagged = !(disagreement.array() <= threshold).all();
  if (msg.coherence_flagged) {
    msg.healthy = false;
    msg.warnings.push_back(coherenceWarning(msg));
  }
}

ParameterEstimate estimateMessage(const StepResult& result, const PolynomialBasis& basis,
                                  const ParameterMapping& mapping,
                                  const HealthSettings& health_settings,
                                  const EstimateContext& context) {
  ParameterEstimate msg;
  msg.load_transfer_ratio = std::numeric_limits<double>::quiet_NaN();  // set by the caller
  msg.header.stamp = context.stamp;
  msg.header.frame_id = context.frame_id;
  msg.sample_index = static_cast<std::uint32_t>(std::max(0, result.index));
  msg.time = result.time;
  msg.method = context.method;
  msg.update_rule = context.update_rule;
  setParameters(msg, mapping, result.mean, result.stddev);
  setBasis(msg, basis);
  if (result.coefficients.size() > 0 && result.coefficients.cols() != basis.size()) {
    throw std::invalid_argument("estimateMessage: coefficients have " +
                                std::to_string(result.coefficients.cols()) + " terms, basis " +
                                std::to_string(basis.size()));
  }
  setCoefficients(msg, result.coefficients);
  if (context.derived != nullptr) {
    setDerived(msg, *context.derived);
    if (!context.derived->empty()) {
      msg.derived_sample_index = static_cast<std::uint32_t>(std::max(0, context.derived_index));
    }
  } else {
    setRolloverOutputs(msg, mapping, basis, result.coefficients);
  }
  setHealth(msg, result.health, result.update.channels, health_settings);
  msg.gated = result.gated;
  msg.rejected_samples = static_cast<std::uint32_t>(std::max(0, result.rejected));
  msg.damping = result.damping;
  msg.reopened = result.reopened;
  msg.load_changed = result.load_reset;
  msg.load_changes = static_cast<std::uint32_t>(std::max(0, result.load_changes));
  msg.load_change_time = result.load_change_time;
  msg.clock_offset = result.clock_offset;
  msg.clock_offset_stddev = result.clock_offset_std;
  if (result.relinearized) {  // docs/method.md §4.9; not a health problem
    msg.warnings.push_back("re-linearised (" + std::to_string(result.restarts) +
                           "): the samples so far re-run from a working prior around the estimate");
  }
  const int unusable = result.forecast.invalid_points + result.forecast.nonfinite_points;
  if (unusable > 0) {  // docs/method.md §4.1: reported, not fatal while enough points remain
    msg.warnings.push_back("forecast: " + std::to_string(unusable) + " of " +
                           std::to_string(result.forecast.points) +
                           " collocation points unusable, left out of the projection (" +
                           result.forecast.first_problem + ")");
  }
  return msg;
}

ParameterEstimate estimateMessage(const StepResult& result, const PcPropagator& propagator,
                                  const HealthSettings& health_settings,
                                  const EstimateContext& context) {
  return estimateMessage(result, propagator.basis(), propagator.mapping(), health_settings,
                         context);
}

ParameterEstimate groundTruthMessage(const ParameterMapping& mapping,
                                     const Eigen::VectorXd& xi_truth, const PolynomialBasis* basis,
                                     const ros::Time& stamp) {
  const int n = mapping.count();
  if (xi_truth.size() != n) {
    throw std::invalid_argument("groundTruthMessage: " + std::to_string(xi_truth.size()) +
                                " germ values for " + std::to_string(n) + " parameters");
  }
  ParameterEstimate msg;
  msg.load_transfer_ratio = std::numeric_limits<double>::quiet_NaN();  // set by the caller
  msg.header.stamp = stamp;
  msg.sample_index = 0;
  msg.time = 0.0;
  msg.method = "truth";
  msg.load_change_time = msg.clock_offset = msg.clock_offset_stddev =
      std::numeric_limits<double>::quiet_NaN();
  const Eigen::VectorXd values = mapping.valuesAtGerms(xi_truth.transpose()).col(0);
  setParameters(msg, mapping, values, Eigen::VectorXd::Zero(n));
  msg.xi_mean = toStd(xi_truth);  // exact, not through the inverse map
  if (basis != nullptr) {
    setBasis(msg, *basis);
    Eigen::MatrixXd coefficients = Eigen::MatrixXd::Zero(n, basis->size());
    coefficients.col(0) = values;
    setCoefficients(msg, coefficients);
  }
  msg.healthy = true;
  msg.band_nested = true;
  msg.mass_outside_support.assign(n, 0.0);
  return msg;
}

// ------------------------------------------------------------------ densities

ParameterPdf pdfMessage(const std::vector<std::string>& names,
                        const std::vector<Histogram>& histograms,
                        const std::vector<double>& mass_outside, int sample_index,
                        const ros::Time& stamp) {
  if (names.size() != histograms.size() ||
      (!mass_outside.empty() && mass_outside.size() != names.size())) {
    throw std::invalid_argument("pdfMessage: " + std::to_string(names.size()) + " names, " +
                                std::to_string(histograms.size()) + " histograms, " +
                                std::to_string(mass_outside.size()) + " outside masses");
  }
  ParameterPdf msg;
  msg.header.stamp = stamp;
  msg.sample_index = static_cast<std::uint32_t>(std::max(0, sample_index));
  msg.names = names;
  for (std::size_t i = 0; i < histograms.size(); ++i) {
    const Histogram& h = histograms[i];
    if (h.edges.size() != h.densities.size() + 1) {
      throw std::invalid_argument("pdfMessage: histogram of '" + names[i] + "' has " +
                                  std::to_string(h.edges.size()) + " edges for " +
                                  std::to_string(h.densities.size()) + " bins");
    }
    msg.bin_count.push_back(static_cast<std::uint32_t>(h.densities.size()));
    msg.edges.insert(msg.edges.end(), h.edges.data(), h.edges.data() + h.edges.size());
    msg.densities.insert(msg.densities.end(), h.densities.data(),
                         h.densities.data() + h.densities.size());
    msg.mass_outside.push_back(mass_outside.empty() ? 0.0 : mass_outside[i]);
  }
  return msg;
}

Eigen::MatrixXd coefficientsOf(const ParameterEstimate& msg) {
  const std::size_t rows = msg.names.size(), cols = msg.term_count;
  if (msg.coefficients.size() != rows * cols) {
    throw std::invalid_argument("ParameterEstimate: " + std::to_string(msg.coefficients.size()) +
                                " coefficients for " + std::to_string(rows) + " parameters x " +
                                std::to_string(cols) + " terms");
  }
  Eigen::MatrixXd c(rows, cols);
  for (std::size_t i = 0; i < rows; ++i) {
    for (std::size_t j = 0; j < cols; ++j) c(i, j) = msg.coefficients[i * cols + j];
  }
  return c;
}

Eigen::MatrixXd derivedCoefficientsOf(const ParameterEstimate& msg) {
  const std::size_t rows = msg.derived_names.size(), cols = msg.term_count;
  if (msg.derived_coefficients.size() != rows * cols) {
    throw std::invalid_argument("ParameterEstimate: " +
                                std::to_string(msg.derived_coefficients.size()) +
                                " derived coefficients for " + std::to_string(rows) +
                                " quantities x " + std::to_string(cols) + " terms");
  }
  Eigen::MatrixXd c(rows, cols);
  for (std::size_t i = 0; i < rows; ++i) {
    for (std::size_t j = 0; j < cols; ++j) c(i, j) = msg.derived_coefficients[i * cols + j];
  }
  return c;
}

}  // namespace pc_ekf
