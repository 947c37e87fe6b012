#include "pc_ekf/ros/estimator_ros.h"

#include <algorithm>
#include <boost/make_shared.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <stdexcept>

#include "pc_ekf/filter/rollover_quantities.h"
#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/ros/estimator_checkpoint.h"
#include "pc_ekf/ros/ros_config.h"

namespace pc_ekf {
namespace {

constexpr double kWarnPeriod = 5.0;  // s between repeated warnings of one kind
constexpr double kMasterCheckPeriod = 1.0;  // s between asking the master whether it knows us

double steadySeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

const char* toString(JointStateProblem p) {
  switch (p) {
    case JointStateProblem::kArrayLength:
      return "array_length";
    case JointStateProblem::kUnknownJoint:
      return "unknown_joint";
    case JointStateProblem::kDuplicateJoint:
      return "duplicate_joint";
    case JointStateProblem::kNonFinite:
      return "non_finite";
  }
  return "?";
}

const char* toString(RoadMode m) {
  switch (m) {
    case RoadMode::kUndecided:
      return "undecided (waiting for the first message)";
    case RoadMode::kTopic:
      return "road/profile topic";
    case RoadMode::kAnalytic:
      return "analytic (config)";
  }
  return "?";
}

// ~checkpoint_file, ~checkpoint_every: node-only private parameters.
void readCheckpointParams(const ros::NodeHandle& pnh, std::string& file, int& every) {
  if (pnh.hasParam(kCheckpointFileParam) && !pnh.getParam(kCheckpointFileParam, file)) {
    throw ConfigError(pnh.resolveName(kCheckpointFileParam) + ": expected a file name (string)");
  }
  if (pnh.hasParam(kCheckpointEveryParam) &&
      (!pnh.getParam(kCheckpointEveryParam, every) || every < 1)) {
    throw ConfigError(pnh.resolveName(kCheckpointEveryParam) +
                      ": expected an integer >= 1 (samples between checkpoints)");
  }
}

}  // namespace

EstimatorRos::EstimatorRos(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& name)
    : name_(name),
      config_(loadRosConfig(pnh, &config_hash_, &start_sensitivity_)),
      nh_(nh),
      pnh_(pnh),
      timeline_(timelineSettings(config_)),
      diagnostics_(nh, pnh, name, config_) {
  joints_ = suspensionJoints(*config_.model_type, config_.node.joint_names);
  // Built now so that a bad road file or collocation design is a start-up error.
  if (config_.road.source == RoadSource::kNone) {
    startRoadFree();
    prior_propagator_ = analytic_propagator_;
  } else if (config_.road.source == RoadSource::kTopic) {
    prior_propagator_ =
        makePropagator(config_, makeModel(config_, std::make_shared<SampledRoad>(
                                                       timelineSettings(config_).contacts)));
  } else {
    analytic_propagator_ = makePropagator(config_, makeModel(config_, makeRoad(config_)));
    prior_propagator_ = analytic_propagator_;
  }
  prepareRolloverRule(prior_propagator_->mapping(), prior_propagator_->basis());
  if (config_.node.publish_pdf) {
    pdfs_ = makePdfSampler(config_, prior_propagator_->basis(),
                           prior_propagator_->parameterCount());
  }
  readCheckpointParams(pnh_, checkpoint_file_, checkpoint_every_);
  if (road_free_ && !checkpoint_file_.empty()) {
    throw ConfigError(pnh_.resolveName(kCheckpointFileParam) +
                      ": checkpoints do not hold road-free inputs (road.source none); unset it");
  }
  // Before any subscription: no callback may see the prior state.
  if (!checkpoint_file_.empty()) {
    resumeFromCheckpoint();
    checkpoint_writer_ = std::make_unique<BackgroundWriter>();
  }

  const int queue = config_.node.queue_size;
  estimate_pub_ = nh_.advertise<ParameterEstimate>("parameter_estimate", queue);
  batch_pub_ = nh_.advertise<ParameterEstimate>("parameter_estimate/batch", 10);
  if (config_.node.publish_pdf) pdf_pub_ = nh_.advertise<ParameterPdf>("parameter_pdf", queue);
  const auto hints = ros::TransportHints().tcpNoDelay();
  if (pdfs_) {
    pdf_worker_ = std::make_unique<PdfWorker>(
        pdfs_, prior_propagator_->mapping().names(),
        [pub = pdf_pub_](const ParameterPdf& msg) mutable { pub.publish(msg); },
        derivedPdfSampler(config_, prior_propagator_->mapping(), prior_propagator_->basis(), pdfs_));
  }
  // joint_states on the receiver thread's own queue (onJointStateReceived).
  ros::SubscribeOptions joint_options;
  joint_options.init<sensor_msgs::JointState>(
      nh_.resolveName("suspension/joint_states"), queue,
      [this](const sensor_msgs::JointState::ConstPtr& msg) { onJointStateReceived(msg); });
  joint_options.transport_hints = hints;
  joint_options.callback_queue = &receive_queue_;
  joint_state_sub_ = nh_.subscribe(joint_options);
  receiver_ = std::make_unique<ros::AsyncSpinner>(1, &receive_queue_);
  receiver_->start();
  if (config_.model_type->twoContacts()) {
    road_sub_ = nh_.subscribe("road/profile", queue, &EstimatorRos::onRoad, this, hints);
  }
  road_heights_sub_ =
      nh_.subscribe("road/heights", queue, &EstimatorRos::onRoadHeights, this, hints);
  if (imuChannels(config_.model_type->channelNames(), config_.measurement.channels).any()) {
    imu_ = std::make_unique<ImuInput>(config_);
    imu_sub_ = nh_.subscribe("imu/data", queue, &EstimatorRos::onImu, this, hints);
    ROS_INFO("%s: IMU channels from %s (aligned to the joint_states stamps)", name_.c_str(),
             nh_.resolveName("imu/data").c_str());
  }
  if (odomSpeedChannel(config_.model_type->channelNames(), config_.measurement.channels) >= 0) {
    odom_ = std::make_unique<ImuInput>(config_, AlignedStream::kOdom);
    odom_sub_ = nh_.subscribe("odom", queue, &EstimatorRos::onOdom, this, hints);
    ROS_INFO("%s: speed from %s twist.twist.linear.x (aligned to the joint_states stamps)",
             name_.c_str(), nh_.resolveName("odom").c_str());
  }
  reset_srv_ = pnh_.advertiseService("reset", &EstimatorRos::onReset, this);
  batch_srv_ = pnh_.advertiseService("estimate_batch", &EstimatorRos::onEstimateBatch, this);

  // Wall-clock timers: they must keep running when /clock stops or jumps back.
  const double wait = std::clamp(config_.node.road_wait_timeout / 4.0, 0.005, 0.05);
  wait_timer_ = nh_.createWallTimer(ros::WallDuration(wait), &EstimatorRos::onWaitTimer, this);
  diagnostics_timer_ = nh_.createWallTimer(ros::WallDuration(diagnostics_.period()),
                                           &EstimatorRos::onDiagnosticsTimer, this);
  // This node's services, roscpp's logger services and (in a nodelet
  // manager) the manager's: whichever exist are registered again after a
  // master restart.
  const std::string node = ros::this_node::getName();
  master_watch_ = std::make_unique<MasterWatch>(
      std::vector<std::string>{reset_srv_.getService(), batch_srv_.getService(),
                               node + "/get_loggers", node + "/set_logger_level",
                               node + "/load_nodelet", node + "/unload_nodelet", node + "/list"},
      kMasterCheckPeriod);
  logStartSensitivity();
  road_free_caveat_ = roadFreeCaveat(config_);
  if (!road_free_caveat_.empty()) ROS_WARN("%s: %s", name_.c_str(), road_free_caveat_.c_str());
  ROS_INFO("%s: estimating from %s (road %s, update %s); config %s", name_.c_str(),
           nh_.resolveName("suspension/joint_states").c_str(),
           toString(config_.road.source).c_str(), toString(config_.update).c_str(),
           config_.source.c_str());
}

EstimatorRos::~EstimatorRos() {
  // No more joint_states handed to this object, none of its callbacks left queued.
  receiver_->stop();
  joint_state_sub_.shutdown();
  nh_.getCallbackQueue()->removeByID(reinterpret_cast<std::uint64_t>(this));
  pdf_worker_.reset();
  if (!checkpoint_writer_) return;
  if (run_) saveCheckpoint();
  checkpoint_writer_->flush();
  const std::uint64_t failed = diagnostics_.upkeep().checkpoint_errors;
  reportCheckpointWrites();
  if (run_ && diagnostics_.upkeep().checkpoint_errors == failed) {
    ROS_INFO("%s: checkpoint %s written at sample %d (shutdown)", name_.c_str(),
             checkpoint_file_.c_str(), run_->samples());
  }
}

void EstimatorRos::logStartSensitivity() {
  const StartSensitivity& s = start_sensitivity_;
  diagnostics_.setSensitivity(s);
  if (s.indices.parameters.empty()) return;
  ROS_INFO("%s: sensitivity over %s; %s", name_.c_str(), s.road.c_str(),
           sensitivityTable(s.indices).c_str());
  for (const auto& line : s.pruned) ROS_INFO("%s: tolerances_prune: %s", name_.c_str(), line.c_str());
  if (!s.note.empty()) ROS_WARN("%s: %s", name_.c_str(), s.note.c_str());
}

void EstimatorRos::startRoadFree() {
  road_free_ = std::make_unique<RoadFreeStream>(config_, RoadFreeStream::inputsFor(config_));
  // ~estimate_batch's posterior-predictive check reads the samples' shared noise.
  if (config_.health.predictive_check) road_free_->trackSerialNoise();
  analytic_propagator_ = makePropagator(config_, road_free_->model());
}

void EstimatorRos::startRun() {
  timeline_.reset();
  run_.reset();
  if (road_free_) startRoadFree();  // the inputs start again with the run
  // A restart must not resume the run that was just abandoned: no write of
  // it may still be waiting or running when the file goes.
  if (checkpoint_writer_) {
    checkpoint_writer_->cancel();
    std::remove(checkpoint_file_.c_str());
  }
  updateRunState();
}

std::unique_ptr<EstimatorRun> EstimatorRos::makeRun() const {
  const bool topic = timeline_.mode() == RoadMode::kTopic;
  return std::make_unique<EstimatorRun>(config_, runPropagator(), pdfs_ != nullptr,
                                        topic ? timeline_.road() : nullptr);
}

std::shared_ptr<const PcPropagator> EstimatorRos::runPropagator() const {
  if (timeline_.mode() == RoadMode::kTopic) {
    return makePropagator(config_, makeModel(config_, timeline_.road()));
  }
  return analytic_propagator_;
}

void EstimatorRos::resumeFromCheckpoint() {
  std::error_code error;
  if (!std::filesystem::exists(checkpoint_file_, error)) {
    ROS_INFO("%s: no checkpoint %s yet: starting from the prior", name_.c_str(),
             checkpoint_file_.c_str());
    return;
  }
  const Checkpoint c = readCheckpoint(checkpoint_file_);
  requireConfigHash(c, config_hash_, checkpoint_file_);
  const RoadMode mode = c.road_mode == "topic" ? RoadMode::kTopic : RoadMode::kAnalytic;
  if (mode == RoadMode::kAnalytic && !analytic_propagator_) {
    throw CheckpointError("checkpoint " + checkpoint_file_ +
                          ": road_mode analytic, but the config's road.source is topic");
  }
  std::optional<ros::Time> last_road;
  if (!c.road.t.empty()) last_road = rosTime(c.road_last_stamp);
  try {
    timeline_.resume(mode, rosTime(c.origin), rosTime(c.last_sample), c.road, last_road);
  } catch (const std::invalid_argument& e) {
    throw CheckpointError("checkpoint " + checkpoint_file_ + ": key 'road.samples': " + e.what());
  }
  run_ = makeRun();
  run_->resumeFrom(c, checkpoint_file_);
  diagnostics_.counters() = countersFromMap(c.counters, checkpoint_file_);
  timeline_.keepRoadFrom(run_->oldestTime());
  last_processed_stamp_ = rosTime(c.last_sample);
  ROS_INFO(
      "%s: resumed from %s at sample %d, t = %.9f s (%s road, origin %u.%09u, %zu road "
      "samples, %zu batch samples; NIS windows restart)",
      name_.c_str(), checkpoint_file_.c_str(), run_->samples(), run_->time(), c.road_mode.c_str(),
      c.origin.sec, c.origin.nsec, c.road.t.size(), run_->batchSamples());
}

void EstimatorRos::saveCheckpoint() {
  CheckpointSnapshot snapshot;
  Checkpoint& c = snapshot.checkpoint;
  c.config_hash = config_hash_;
  c.road_mode = timeline_.mode() == RoadMode::kTopic ? "topic" : "analytic";
  c.origin = checkpointStamp(timeline_.origin().value_or(ros::Time()));
  c.last_sample = checkpointStamp(last_processed_stamp_);
  run_->saveTo(snapshot);
  if (timeline_.mode() == RoadMode::kTopic) {
    c.road = timeline_.roadFrom(run_->oldestTime());
    if (const auto last = timeline_.lastRoadStamp()) c.road_last_stamp = checkpointStamp(*last);
  }
  c.counters = counterMap(diagnostics_.counters());
  checkpoint_writer_->submit(
      [snapshot = std::move(snapshot), path = checkpoint_file_] { writeCheckpoint(snapshot, path); });
}

void EstimatorRos::reportCheckpointWrites() {
  if (!checkpoint_writer_) return;
  NodeUpkeep& upkeep = diagnostics_.upkeep();
  for (const std::string& error : checkpoint_writer_->takeErrors()) {
    ++upkeep.checkpoint_errors;
    upkeep.last_checkpoint_error = error;
    ROS_ERROR_THROTTLE(kWarnPeriod, "%s: %s", name_.c_str(), error.c_str());
  }
  upkeep.checkpoints_written = checkpoint_writer_->written();
  upkeep.checkpoints_superseded = checkpoint_writer_->superseded();
}

void EstimatorRos::rejectSample(const std::string& reason, const std::string& detail) {
  ++diagnostics_.counters().samples_rejected[reason];
  ROS_WARN_THROTTLE(kWarnPeriod, "%s: joint_states rejected (%s): %s", name_.c_str(),
                    reason.c_str(), detail.c_str());
}

namespace {

// One processNext() on the node's callback queue.
class ProcessNextCallback : public ros::CallbackInterface {
 public:
  explicit ProcessNextCallback(std::function<void()> f) : f_(std::move(f)) {}
  CallResult call() override {
    f_();
    return Success;
  }

 private:
  std::function<void()> f_;
};

}  // namespace

void EstimatorRos::onJointStateReceived(const sensor_msgs::JointState::ConstPtr& msg) {
  {
    std::lock_guard<std::mutex> lock(inbox_mutex_);
    if (inbox_.size() >= static_cast<std::size_t>(config_.node.queue_size)) {
      inbox_.pop_front();  // as a full subscriber queue does: the oldest goes
      ++diagnostics_.backlog().queue_overflow;
    }
    inbox_.push_back(msg);
    newest_received_ = std::max(newest_received_, msg->header.stamp);
  }
  nh_.getCallbackQueue()->addCallback(
      boost::make_shared<ProcessNextCallback>([this] { processNext(); }),
      reinterpret_cast<std::uint64_t>(this));
}

void EstimatorRos::processNext() {
  sensor_msgs::JointState::ConstPtr msg;
  {
    std::lock_guard<std::mutex> lock(inbox_mutex_);
    if (inbox_.empty()) return;  // dropped by an overflow
    msg = inbox_.front();
    inbox_.pop_front();
  }
  onJointState(msg);
}

void EstimatorRos::onJointState(const sensor_msgs::JointState::ConstPtr& msg) {
  const double now = steadySeconds();
  EstimatorCounters& counters = diagnostics_.counters();
  ++counters.samples_received;
  const JointStateConversion conv = measurementFromJointState(*msg, 0.0, joints_);
  counters.nan_elements += static_cast<std::uint64_t>(conv.nan_elements);
  bool malformed = false;
  for (std::size_t i = 0; i < conv.problem_kinds.size(); ++i) {
    if (conv.problem_kinds[i] == JointStateProblem::kArrayLength) {
      malformed = true;  // names and values cannot be matched: the whole message goes
    } else {
      ++counters.elements_rejected[toString(conv.problem_kinds[i])];
      ROS_WARN_THROTTLE(kWarnPeriod, "%s: joint_states element rejected: %s", name_.c_str(),
                        conv.problems[i].c_str());
    }
  }
  if (malformed) {
    rejectSample("array_length", conv.problems.front());
    return;
  }
  if (conv.empty()) {
    rejectSample("no_observed_channel", "no finite position or velocity of the suspension joints");
    return;
  }
  if (imu_) {
    imu_->addSample(msg->header.stamp, conv.measurement, now);
    releaseImu(now);
    return;
  }
  addSampleToOdom(msg->header.stamp, conv.measurement, now, now);
}

void EstimatorRos::addSampleToOdom(const ros::Time& stamp, const Measurement& m, double arrival,
                                   double now) {
  if (!odom_) {
    addSample(stamp, m, arrival);
    return;
  }
  // The odom wait runs from the moment the sample is handed on (after the IMU's).
  odom_->addSample(stamp, m, now);
  releaseOdom(now);
}

void EstimatorRos::addSample(const ros::Time& stamp, const Measurement& m, double arrival) {
  EstimatorCounters& counters = diagnostics_.counters();
  StampVerdict v = timeline_.addSample(stamp, m, arrival);
  if (v == StampVerdict::kTimeJump && config_.node.reset_on_time_jump) {
    ROS_WARN("%s: joint_states stamp jumped back in time: reset to the prior", name_.c_str());
    ++counters.time_jump_resets;
    startRun();
    v = timeline_.addSample(stamp, m, arrival);
  }
  if (v != StampVerdict::kAccepted) {
    rejectSample(toString(v), "stamp " + std::to_string(stamp.toSec()));
    return;
  }
  processReleased();
}

void EstimatorRos::onImu(const sensor_msgs::Imu::ConstPtr& msg) {
  const double now = steadySeconds();
  const std::string problem = imu_->addImu(*msg, now);
  if (!problem.empty()) {
    ROS_WARN_THROTTLE(kWarnPeriod, "%s: imu/data stamped %.9f: %s", name_.c_str(),
                      msg->header.stamp.toSec(), problem.c_str());
  }
  releaseImu(now);
}

void EstimatorRos::releaseImu(double now) {
  const std::uint64_t expired = imu_->stats().samples_without_imu.count("wait_expired")
                                    ? imu_->stats().samples_without_imu.at("wait_expired")
                                    : 0;
  for (const ImuReleased& s : imu_->release(now)) addSampleToOdom(s.stamp, s.measurement, s.arrival, now);
  const auto& without = imu_->stats().samples_without_imu;
  if (without.count("wait_expired") && without.at("wait_expired") > expired) {
    ROS_WARN_THROTTLE(kWarnPeriod,
                      "%s: no imu/data message reached a joint_states stamp within %.3f s "
                      "(node.road_wait_timeout): samples go on without IMU channels",
                      name_.c_str(), config_.node.road_wait_timeout);
  }
}

void EstimatorRos::onOdom(const nav_msgs::Odometry::ConstPtr& msg) {
  const double now = steadySeconds();
  const std::string problem = odom_->addOdom(*msg, now);
  if (!problem.empty()) {
    ROS_WARN_THROTTLE(kWarnPeriod, "%s: odom stamped %.9f: %s", name_.c_str(),
                      msg->header.stamp.toSec(), problem.c_str());
  }
  releaseOdom(now);
}

void EstimatorRos::releaseOdom(double now) {
  const auto expiredOf = [&] {
    const auto& without = odom_->stats().samples_without_imu;
    return without.count("wait_expired") ? without.at("wait_expired") : std::uint64_t{0};
  };
  const std::uint64_t expired = expiredOf();
  for (const ImuReleased& s : odom_->release(now)) addSample(s.stamp, s.measurement, s.arrival);
  if (expiredOf() > expired) {
    ROS_WARN_THROTTLE(kWarnPeriod,
                      "%s: no odom message reached a joint_states stamp within %.3f s "
                      "(node.road_wait_timeout): samples go on without the speed",
                      name_.c_str(), config_.node.road_wait_timeout);
  }
}

void EstimatorRos::onRoad(const RoadProfile::ConstPtr& msg) {
  addRoad(msg->header.stamp, {msg->left, msg->right}, "road/profile");
}

void EstimatorRos::onRoadHeights(const RoadHeights::ConstPtr& msg) {
  std::vector<double> heights;
  const std::string problem =
      roadHeightsInOrder(*msg, config_.model_type->contactNames(), &heights);
  if (!problem.empty()) {
    EstimatorCounters& counters = diagnostics_.counters();
    ++counters.road_received;
    ++counters.road_rejected["contacts"];
    ROS_WARN_THROTTLE(kWarnPeriod, "%s: road/heights rejected (%s), stamp %.9f", name_.c_str(),
                      problem.c_str(), msg->header.stamp.toSec());
    return;
  }
  addRoad(msg->header.stamp, heights, "road/heights");
}

void EstimatorRos::addRoad(const ros::Time& stamp, const std::vector<double>& heights,
                           const char* topic) {
  const double now = steadySeconds();
  EstimatorCounters& counters = diagnostics_.counters();
  ++counters.road_received;
  StampVerdict v = timeline_.addRoad(stamp, heights, now);
  if (v == StampVerdict::kTimeJump && config_.node.reset_on_time_jump) {
    ROS_WARN("%s: %s stamp jumped back in time: reset to the prior", name_.c_str(), topic);
    ++counters.time_jump_resets;
    startRun();
    v = timeline_.addRoad(stamp, heights, now);
  }
  if (v == StampVerdict::kAccepted) {
    ++counters.road_accepted;
    processReleased();
    return;
  }
  ++counters.road_rejected[toString(v)];
  if (v != StampVerdict::kIgnored) {
    ROS_WARN_THROTTLE(kWarnPeriod, "%s: %s rejected (%s), stamp %.9f", name_.c_str(), topic,
                      toString(v), stamp.toSec());
  }
}

void EstimatorRos::onWaitTimer(const ros::WallTimerEvent&) {
  if (imu_ && imu_->waiting() > 0) releaseImu(steadySeconds());
  if (odom_ && odom_->waiting() > 0) releaseOdom(steadySeconds());
  if (timeline_.pendingCount() > 0) processReleased();
}

void EstimatorRos::onDiagnosticsTimer(const ros::WallTimerEvent&) {
  updateRunState();
  if (imu_) diagnostics_.setImu(imu_->stats(), steadySeconds());
  if (odom_) diagnostics_.setOdom(odom_->stats(), steadySeconds());
  {
    NodeBacklog& b = diagnostics_.backlog();
    std::lock_guard<std::mutex> lock(inbox_mutex_);
    b.queue_depth = inbox_.size();
    b.lag = last_processed_stamp_.isZero()
                ? 0.0
                : std::max(0.0, (newest_received_ - last_processed_stamp_).toSec());
    b.pdf_queue = pdf_worker_ ? pdf_worker_->queued() : 0;
    b.pdf_dropped = pdf_worker_ ? pdf_worker_->dropped() : 0;
    b.rerun_pending_swap = run_ ? run_->pendingSwap() : 0;
    b.late_swaps = run_ ? run_->lateSwaps() : 0;
  }
  reportCheckpointWrites();
  const MasterStatus master = master_watch_->status();
  NodeUpkeep& upkeep = diagnostics_.upkeep();
  upkeep.master_state = master.reachable ? "connected" : "unreachable";
  upkeep.master_pid = master.pid;
  upkeep.master_restarts = master.restarts;
  upkeep.master_last_change = master.last_change;
  upkeep.master_last_report = master.last_report;
  diagnostics_.publish();
}

void EstimatorRos::updateRunState() {
  std::string origin;
  if (const auto o = timeline_.origin()) {
    char text[32];
    std::snprintf(text, sizeof(text), "%u.%09u", o->sec, o->nsec);
    origin = text;
  }
  const char* road = road_free_ ? "none (road-free: the suspension readings drive the body)"
                               : toString(timeline_.mode());
  diagnostics_.setRunState(road, origin, timeline_.pendingCount(),
                           timeline_.roadCount());
}

void EstimatorRos::processReleased() {
  DroppedSamples dropped;
  const std::vector<ReleasedSample> ready = timeline_.release(steadySeconds(), &dropped);
  if (dropped.no_road > 0) {
    diagnostics_.counters().samples_rejected["no_road"] += dropped.no_road;
    ROS_WARN_THROTTLE(kWarnPeriod, "%s: no road/profile data within %.3f s (road.source: topic)",
                      name_.c_str(), config_.node.road_wait_timeout);
  }
  if (dropped.before_origin > 0) {
    diagnostics_.counters().samples_rejected["before_origin"] += dropped.before_origin;
  }
  for (const ReleasedSample& s : ready) process(s);
}

void EstimatorRos::process(const ReleasedSample& sample) {
  EstimatorCounters& counters = diagnostics_.counters();
  if (!run_) run_ = makeRun();
  if (sample.road_held) {
    ++counters.road_wait_expired;
    ROS_WARN_THROTTLE(kWarnPeriod,
                      "%s: road data did not reach t = %.6f s within %.3f s; road held at its "
                      "last value",
                      name_.c_str(), sample.measurement.time, config_.node.road_wait_timeout);
  }
  const double start = steadySeconds();
  Measurement outputs;
  if (road_free_) {
    const std::string problem = road_free_->add(sample.measurement, &outputs);
    if (!problem.empty()) {
      rejectSample("road_free_input", problem);
      return;
    }
  }
  SampleEstimate e;
  try {
    e = run_->process(road_free_ ? outputs : sample.measurement, sample.stamp);
  } catch (const std::invalid_argument& err) {  // checked before; the filter has the last word
    rejectSample("filter_refused", err.what());
    return;
  }
  const double done = steadySeconds();
  if (!road_free_caveat_.empty()) e.estimate.healthy = false;  // roadFreeCaveat
  estimate_pub_.publish(e.estimate);
  if (e.pdf && pdf_worker_) pdf_worker_->submit(std::move(*e.pdf));
  timeline_.keepRoadFrom(run_->oldestTime());
  // Road-free: the inputs no filter or batch reads again go (flat memory over hours).
  if (road_free_) road_free_->forgetInputs(run_->oldestTime(), run_->batchUntil());

  ++counters.samples_processed;
  counters.non_finite_updates += e.non_finite + e.coherence_non_finite;
  counters.batch_not_kept += e.batch_full;
  last_processed_stamp_ = sample.stamp;
  {
    NodeBacklog& b = diagnostics_.backlog();
    std::lock_guard<std::mutex> lock(inbox_mutex_);
    b.queue_depth = inbox_.size();
    b.max_queue_depth = std::max(b.max_queue_depth, b.queue_depth);
    b.lag = std::max(0.0, (newest_received_ - sample.stamp).toSec());
    b.max_lag = std::max(b.max_lag, b.lag);
  }
  if (checkpoint_writer_ && run_->samples() % checkpoint_every_ == 0) {
    // A failed write is logged (reportCheckpointWrites); estimating goes on.
    reportCheckpointWrites();
    saveCheckpoint();
  }
  if (e.non_finite) {
    ROS_ERROR_THROTTLE(kWarnPeriod, "%s: non-finite filter update at t = %.6f s (sample %u)",
                       name_.c_str(), sample.measurement.time, e.estimate.sample_index);
  }
  LastUpdate& last = diagnostics_.last();
  last.any = true;
  last.sample_index = e.estimate.sample_index;
  last.time = sample.measurement.time;
  last.latency = done - sample.arrival;
  last.compute = done - start;
  last.health = e.health;
  last.coherence_flagged = e.estimate.coherence_flagged;
  last.healthy = e.estimate.healthy;
  last.non_finite = e.non_finite;
  last.warnings = e.estimate.warnings;
  last.load_changes = e.estimate.load_changes;
  last.load_change_time = e.estimate.load_change_time;
  last.clock_offset = e.estimate.clock_offset;
  last.clock_offset_std = e.estimate.clock_offset_stddev;
  if (road_free_) {
    last.standing = road_free_->standing();
    last.stops = road_free_->stops();
    last.standing_samples = road_free_->standingSamples();
  }
  if (e.estimate.load_changed) {
    last.load_found_at = sample.measurement.time;
    last.load_summary.clear();
    std::string said;
    for (std::size_t i = 0; i < e.estimate.names.size(); ++i) {
      if (e.estimate.names[i].rfind("added_mass", 0) != 0) continue;
      char line[160];
      std::snprintf(line, sizeof line, "%s %.4g +- %.2g", e.estimate.names[i].c_str(),
                    e.estimate.mean[i], e.estimate.stddev[i]);
      last.load_summary.push_back(line);
      said += (said.empty() ? "" : ", ") + std::string(line);
    }
    ROS_INFO("%s: load change found at t = %.3f s (it began at t = %.3f s); the load afresh: %s",
             name_.c_str(), sample.measurement.time, e.estimate.load_change_time, said.c_str());
  }
}

bool EstimatorRos::onReset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  const int samples = run_ ? run_->samples() : 0;
  if (imu_) imu_->reset();
  if (odom_) odom_->reset();
  startRun();
  ++diagnostics_.counters().resets;
  diagnostics_.last() = LastUpdate{};
  const EstimatorRun prior(config_, prior_propagator_, false);
  const ParameterEstimate msg = prior.priorEstimate(ros::Time::now());
  estimate_pub_.publish(msg);
  std::string text = "reset after " + std::to_string(samples) + " samples; prior";
  for (std::size_t i = 0; i < msg.names.size(); ++i) {
    text += (i ? ", " : ": ") + msg.names[i] + " " + std::to_string(msg.mean[i]) + " +- " +
            std::to_string(msg.stddev[i]);
  }
  res.success = true;
  res.message = text;
  ROS_INFO("%s: %s", name_.c_str(), text.c_str());
  return true;
}

bool EstimatorRos::onEstimateBatch(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  if (!run_) {
    res.success = false;
    res.message = toString(config_.node.batch_method) + ": no samples since the last reset";
    return true;
  }
  const BatchEstimate b = run_->batch(timeline_.roadHistoryComplete());
  if (b.ok) batch_pub_.publish(b.estimate);
  res.success = b.ok;
  res.message = b.summary;
  ROS_INFO("%s: ~estimate_batch: %s", name_.c_str(), b.summary.c_str());
  return true;
}

}  // namespace pc_ekf
