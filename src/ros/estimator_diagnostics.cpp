#include "pc_ekf/ros/estimator_diagnostics.h"

#include <sstream>

namespace pc_ekf {
namespace {

using diagnostic_msgs::DiagnosticStatus;

std::uint64_t sum(const std::map<std::string, std::uint64_t>& m) {
  std::uint64_t n = 0;
  for (const auto& kv : m) n += kv.second;
  return n;
}

std::string joined(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& s : items) out += (out.empty() ? "" : "; ") + s;
  return out;
}

}  // namespace

std::uint64_t EstimatorCounters::rejectedTotal() const {
  return sum(samples_rejected) + sum(elements_rejected) + sum(road_rejected);
}

EstimatorDiagnostics::EstimatorDiagnostics(ros::NodeHandle nh, ros::NodeHandle pnh,
                                           const std::string& node_name,
                                           const EstimatorConfig& config)
    : updater_(nh, pnh, node_name), config_(config), reported_at_(ros::WallTime::now()) {
  updater_.setHardwareID("none");  // a software estimator
  updater_.add("configuration", this, &EstimatorDiagnostics::reportConfiguration);
  updater_.add("input", this, &EstimatorDiagnostics::reportInput);
  updater_.add("filter health", this, &EstimatorDiagnostics::reportHealth);
  updater_.add("checkpoints and master", this, &EstimatorDiagnostics::reportUpkeep);
  updater_.add("sensitivity", this, &EstimatorDiagnostics::reportSensitivity);
  if (imuChannels(config.model_type->channelNames(), config.measurement.channels).any()) {
    updater_.add("imu", this, &EstimatorDiagnostics::reportImu);
  }
  if (odomSpeedChannel(config.model_type->channelNames(), config.measurement.channels) >= 0) {
    updater_.add("odom", this, &EstimatorDiagnostics::reportOdom);
  }
  if (config.safeguards.reopen.mode == ReopenMode::kLoad || config.safeguards.horizon.clock_offset > 0.0 ||
      config.measurement.standstill > 0.0) {
    updater_.add("load and clock", this, &EstimatorDiagnostics::reportLoad);
  }
}

void EstimatorDiagnostics::setRunState(const std::string& road_mode, const std::string& origin,
                                       std::size_t pending, std::size_t road_samples) {
  road_mode_ = road_mode;
  origin_ = origin;
  pending_ = pending;
  road_samples_ = road_samples;
}

void EstimatorDiagnostics::reportConfiguration(diagnostic_updater::DiagnosticStatusWrapper& s) {
  const EstimatorConfig& c = config_;
  std::string parameters;
  for (const auto& u : c.uncertain) parameters += (parameters.empty() ? "" : ", ") + u.name;
  std::ostringstream m;
  m << "estimating " << parameters << "; road " << toString(c.road.source) << ", update "
    << toString(c.update) << ", batch " << toString(c.node.batch_method);
  s.summary(DiagnosticStatus::OK, m.str());
  s.add("config source", c.source);
  s.add("parameters", parameters);
  s.add("road source", toString(c.road.source));
  s.add("update rule", toString(c.update));
  s.add("pc order", c.pc_order);
  s.add("collocation points", c.collocation.points);
  std::string joints;
  for (const auto& j : c.node.joint_names) joints += (joints.empty() ? "" : ", ") + j;
  s.add("joints", joints);
  s.add("batch method", toString(c.node.batch_method));
  s.add("coherence check", c.node.coherence_check);
  s.add("coherence decimation", c.health.coherence_decimation);
  s.add("publish pdf", c.node.publish_pdf);
  s.add("reset on time jump", c.node.reset_on_time_jump);
  s.add("road wait timeout", c.node.road_wait_timeout);
  s.add("queue size", c.node.queue_size);
}

void EstimatorDiagnostics::reportInput(diagnostic_updater::DiagnosticStatusWrapper& s) {
  const EstimatorCounters& c = counters_;
  const ros::WallTime now = ros::WallTime::now();
  const double elapsed = (now - reported_at_).toSec();
  const double rate =
      elapsed > 0.0 ? static_cast<double>(c.samples_received - reported_received_) / elapsed : 0.0;
  const std::uint64_t rejected = c.rejectedTotal();
  const bool new_rejections = rejected > reported_rejected_;
  const bool new_expired = c.road_wait_expired > reported_expired_;
  reported_at_ = now;
  reported_received_ = c.samples_received;
  reported_rejected_ = rejected;
  reported_expired_ = c.road_wait_expired;

  std::ostringstream m;
  m << c.samples_processed << " samples processed, " << rejected << " inputs rejected";
  if (new_rejections) m << " (new since the last report)";
  if (new_expired) m << "; road data late, held at its last value";
  s.summary(new_rejections || new_expired ? DiagnosticStatus::WARN : DiagnosticStatus::OK, m.str());
  s.add("input rate (samples/s)", rate);
  const NodeBacklog& b = backlog_;
  s.add("lag (ms, newest received - newest processed stamp)", 1e3 * b.lag);
  s.add("max lag (ms)", 1e3 * b.max_lag);
  s.add("queue depth (received, not processed)", b.queue_depth);
  s.add("max queue depth", b.max_queue_depth);
  s.add("queue overflow (dropped)", b.queue_overflow);
  s.add("parameter_pdf being drawn", b.pdf_queue);
  s.add("parameter_pdf dropped (queue full)", b.pdf_dropped);
  s.add("deferred re-run swap after sample", b.rerun_pending_swap);
  s.add("deferred re-runs waited for", b.late_swaps);
  s.add("samples received", c.samples_received);
  s.add("samples processed", c.samples_processed);
  s.add("samples rejected", sum(c.samples_rejected));
  for (const auto& kv : c.samples_rejected) s.add("samples rejected: " + kv.first, kv.second);
  s.add("elements rejected", sum(c.elements_rejected));
  for (const auto& kv : c.elements_rejected) s.add("elements rejected: " + kv.first, kv.second);
  s.add("nan elements (not observed)", c.nan_elements);
  s.add("road received", c.road_received);
  s.add("road accepted", c.road_accepted);
  for (const auto& kv : c.road_rejected) s.add("road rejected: " + kv.first, kv.second);
  s.add("road wait expired", c.road_wait_expired);
  s.add("batch samples not kept", c.batch_not_kept);
  s.add("resets", c.resets);
  s.add("time jump resets", c.time_jump_resets);
  s.add("road mode", road_mode_);
  s.add("time origin (stamp)", origin_);
  s.add("pending samples", pending_);
  s.add("road samples buffered", road_samples_);
}

void EstimatorDiagnostics::reportHealth(diagnostic_updater::DiagnosticStatusWrapper& s) {
  const LastUpdate& u = last_;
  s.add("non-finite updates", counters_.non_finite_updates);
  if (!u.any) {
    s.summary(DiagnosticStatus::OK, "waiting for samples");
    return;
  }
  const HealthStatus& h = u.health;
  if (u.non_finite || h.non_finite || h.forecast_failed) {
    s.summary(DiagnosticStatus::ERROR, "filter diverged: " + joined(u.warnings));
  } else if (h.rates.flagged()) {
    // The safeguards act more often than the model allows (docs/method.md
    // §5.9): the data are not explained, whatever the windowed NIS says.
    s.summary(DiagnosticStatus::ERROR,
              "safeguards beyond their expected rates: " + joined(h.rates.warnings()));
  } else if (!u.healthy || h.support_exceeded || h.loo_exceeded) {
    s.summary(DiagnosticStatus::WARN, joined(u.warnings));
  } else {
    s.summary(DiagnosticStatus::OK, "healthy");
  }
  s.add("sample index", u.sample_index);
  s.add("time (s)", u.time);
  s.add("last update latency (s)", u.latency);
  s.add("last update compute time (s)", u.compute);
  s.add("nis", h.nis);
  s.add("nis outside bounds", h.nis_outside);
  s.add("nis window mean", h.nis_window_mean);
  s.add("nis window outside bounds", h.nis_window_outside);
  s.add("support exceeded", h.support_exceeded);
  s.add("non finite", u.non_finite || h.non_finite);
  s.add("forecast failed", h.forecast_failed);
  s.add("band nested (informational)", h.band_nested);
  s.add("coherence flagged", u.coherence_flagged);
  // The safeguards' rates (docs/method.md §5.9): window = last health.rate_window s.
  const SafeguardRates& r = h.rates;
  const std::pair<const char*, const SafeguardRate*> rates[] = {{"gated samples", &r.gated},
                                                               {"damped updates", &r.damped},
                                                               {"re-opens", &r.reopened},
                                                               {"support exceeded", &r.support}};
  for (const auto& [name, rate] : rates) {
    const std::string n = name;
    if (rate == &r.reopened) {
      s.add(n + " per s (run)", rate->run.exposure > 0.0 ? rate->run.count / rate->run.exposure : 0.0);
    } else {
      s.add(n + " fraction (run)", rate->run.trials > 0
                                        ? static_cast<double>(rate->run.count) / rate->run.trials
                                        : 0.0);
    }
    s.add(n + " (window / expected)", std::to_string(rate->window.count) + " / " +
                                          std::to_string(rate->window.expected));
    s.add(n + " (run / expected)",
          std::to_string(rate->run.count) + " / " + std::to_string(rate->run.expected));
    s.add(n + " P(window, run)",
          std::to_string(rate->window.tail) + ", " + std::to_string(rate->run.tail));
    s.add(n + " rate flagged", rate->flagged());
  }
  s.add("safeguard rates flagged", r.flagged());
  const std::vector<std::string>& channels = config_.model_type->channelNames();
  for (Eigen::Index i = 0; i < h.loo_error.size(); ++i) {
    const std::string name =
        i < static_cast<Eigen::Index>(channels.size()) ? channels[i] : std::to_string(i);
    s.add("projection loo error " + name, h.loo_error[i]);
  }
  s.add("projection loo warning threshold", config_.collocation.loo_warning);
  s.add("projection loo exceeded", h.loo_exceeded);
  s.add("healthy", u.healthy);
}

void EstimatorDiagnostics::reportUpkeep(diagnostic_updater::DiagnosticStatusWrapper& s) {
  const NodeUpkeep& u = upkeep_;
  std::ostringstream m;
  m << u.checkpoints_written << " checkpoints written";
  if (u.master_restarts > 0) m << "; re-registered with " << u.master_restarts << " new master(s)";
  if (u.master_state != "connected") m << "; master " << u.master_state;
  const bool new_errors = u.checkpoint_errors > reported_checkpoint_errors_;
  reported_checkpoint_errors_ = u.checkpoint_errors;
  if (new_errors) m << "; checkpoint write failed: " << u.last_checkpoint_error;
  const auto level = new_errors ? DiagnosticStatus::ERROR
                     : u.master_state != "connected" ? DiagnosticStatus::WARN
                                                     : DiagnosticStatus::OK;
  s.summary(level, m.str());
  s.add("checkpoints written", u.checkpoints_written);
  s.add("checkpoints superseded (latest wins)", u.checkpoints_superseded);
  s.add("checkpoint write errors", u.checkpoint_errors);
  s.add("last checkpoint error", u.last_checkpoint_error);
  s.add("master", u.master_state);
  s.add("master pid", u.master_pid);
  s.add("master restarts (re-registered)", u.master_restarts);
  s.add("last re-registration (wall time)", u.master_last_change);
  s.add("last re-registration", u.master_last_report);
}

void EstimatorDiagnostics::reportSensitivity(diagnostic_updater::DiagnosticStatusWrapper& s) {
  const PriorSensitivity& p = sensitivity_.indices;
  if (p.parameters.empty()) {
    s.summary(DiagnosticStatus::OK, "no tolerances: nothing to rank");
    return;
  }
  std::ostringstream m;
  const std::vector<int> order = p.ranking();
  m << "largest total Sobol index: " << p.parameters[order.front()] << " "
    << p.largestTotal(order.front()) << ", smallest: " << p.parameters[order.back()] << " "
    << p.largestTotal(order.back());
  if (!sensitivity_.pruned.empty()) m << "; " << sensitivity_.pruned.size() << " tolerances fixed";
  s.summary(DiagnosticStatus::OK, m.str());
  s.add("road", sensitivity_.road);
  for (int i : order) s.add(p.parameters[i] + " (largest total index)", p.largestTotal(i));
  for (const auto& line : sensitivity_.pruned) s.add("fixed", line);
  if (!sensitivity_.note.empty()) s.add("note", sensitivity_.note);
}

}  // namespace pc_ekf
