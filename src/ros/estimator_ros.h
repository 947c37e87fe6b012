// estimator_node's logic, shared by the executable and the nodelet
// (pc_ekf/EstimatorNodelet): converts messages, orders and queues samples
// (EstimatorTimeline), runs the filters (EstimatorRun), publishes and reports.
// All names are relative (several vehicles side by side in namespaces).
// Callbacks, timers and services must run on one thread (ros::spin, or the
// nodelet's single-threaded queue): nothing there is locked. Two threads of
// the node's own hand work to it (docs/realtime.md): a receiver takes
// joint_states off the subscription into inbox_ (so that the lag and queue
// depth are known), and the PDF worker draws parameter_pdf messages; the
// filters' deferred re-runs have threads of their own (OneStepFilter).
#pragma once

#include <pc_ekf/RoadHeights.h>
#include <pc_ekf/RoadProfile.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>
#include <std_srvs/Trigger.h>

#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>

#include "pc_ekf/filter/pc_propagator.h"
#include "pc_ekf/io/background_writer.h"
#include "pc_ekf/io/estimator_config.h"
#include "pc_ekf/io/road_free_stream.h"
#include "pc_ekf/io/start_sensitivity.h"
#include "pc_ekf/ros/estimator_diagnostics.h"
#include "pc_ekf/ros/estimator_run.h"
#include "pc_ekf/ros/estimator_timeline.h"
#include "pc_ekf/ros/imu_input.h"
#include "pc_ekf/ros/master_watch.h"
#include "pc_ekf/ros/message_conversion.h"

namespace pc_ekf {

class EstimatorRos {
 public:
  // Reads the configuration (ros_config.h) and starts. Throws ConfigError
  // naming the key and value when the configuration is invalid.
  // With ~checkpoint_file set and the file present, resumes from it; throws
  // CheckpointError when it is unreadable or from another configuration.
  EstimatorRos(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& name);
  // Writes the checkpoint (when enabled) so that a restart continues the run,
  // and waits for the write.
  ~EstimatorRos();

 private:
  // Receiver thread: queues the message and schedules processNext().
  // The tolerances' sensitivity (computed while the config was loaded): once in
  // the log, and on /diagnostics.
  void logStartSensitivity();
  void onJointStateReceived(const sensor_msgs::JointState::ConstPtr& msg);
  // Main thread: the oldest queued joint_states message.
  void processNext();
  void onJointState(const sensor_msgs::JointState::ConstPtr& msg);
  // A converted sample to the timeline (after its IMU channels, if any).
  void addSample(const ros::Time& stamp, const Measurement& m, double arrival);
  // imu/data (docs/nodes.md "Clocks"): the samples the IMU alignment releases.
  void onImu(const sensor_msgs::Imu::ConstPtr& msg);
  void releaseImu(double now);
  // odom (docs/nodes.md "Clocks"): the speed, aligned after the IMU channels.
  void onOdom(const nav_msgs::Odometry::ConstPtr& msg);
  void releaseOdom(double now);
  // A sample with its IMU channels (if any): on to the odom alignment, or to
  // addSample when the speed is not read.
  void addSampleToOdom(const ros::Time& stamp, const Measurement& m, double arrival, double now);
  void onRoad(const RoadProfile::ConstPtr& msg);
  void onRoadHeights(const RoadHeights::ConstPtr& msg);
  void addRoad(const ros::Time& stamp, const std::vector<double>& heights, const char* topic);
  void onWaitTimer(const ros::WallTimerEvent&);
  void onDiagnosticsTimer(const ros::WallTimerEvent&);
  bool onReset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  bool onEstimateBatch(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);

  // Feeds the filter every sample the timeline releases and publishes.
  void processReleased();
  void process(const ReleasedSample& sample);
  void startRun();
  void startRoadFree();
  void rejectSample(const std::string& reason, const std::string& detail);
  void updateRunState();
  // The filters' propagator for the current road mode (topic: the timeline's road).
  std::shared_ptr<const PcPropagator> runPropagator() const;
  std::unique_ptr<EstimatorRun> makeRun() const;
  void resumeFromCheckpoint();
  // Hands the run's state to the writer thread (latest wins).
  void saveCheckpoint();
  // Logs the writer's failed writes (on this thread) and updates diagnostics.
  void reportCheckpointWrites();

  std::string name_;
  std::uint64_t config_hash_ = 0;  // set while config_ is loaded (declared before it)
  StartSensitivity start_sensitivity_;  // likewise
  EstimatorConfig config_;
  SuspensionJoints joints_;
  ros::NodeHandle nh_, pnh_;
  std::shared_ptr<const PcPropagator> analytic_propagator_;  // null for road.source: topic
  std::shared_ptr<const PcPropagator> prior_propagator_;     // for the prior message
  std::shared_ptr<const ParameterPdfSampler> pdfs_;          // null: no parameter_pdf
  EstimatorTimeline timeline_;
  // road.source none: the run's inputs (suspension readings, gyro) and the
  // model they drive, renewed with every run (startRun).
  std::unique_ptr<RoadFreeStream> road_free_;
  std::string road_free_caveat_;  // roadFreeCaveat: every estimate reported not healthy
  std::unique_ptr<ImuInput> imu_;  // null: measurement.channels select no IMU channel
  std::unique_ptr<ImuInput> odom_;  // null: measurement.channels do not select speed
  std::unique_ptr<EstimatorRun> run_;  // created at the run's first released sample
  std::unique_ptr<PdfWorker> pdf_worker_;  // null: no parameter_pdf
  EstimatorDiagnostics diagnostics_;
  std::string checkpoint_file_;  // "" = no checkpoints
  int checkpoint_every_ = 100;   // samples of the run between writes
  // Checkpoint files are written on its thread: a write of 10^5 kept samples
  // takes ~150 ms, far more than the sampling interval.
  std::unique_ptr<BackgroundWriter> checkpoint_writer_;
  ros::Time last_processed_stamp_;

  // joint_states received, not yet processed (receiver thread -> main thread).
  std::mutex inbox_mutex_;
  std::deque<sensor_msgs::JointState::ConstPtr> inbox_;
  ros::Time newest_received_;  // guarded by inbox_mutex_
  ros::CallbackQueue receive_queue_;
  std::unique_ptr<ros::AsyncSpinner> receiver_;

  ros::Subscriber joint_state_sub_, road_sub_, road_heights_sub_, imu_sub_, odom_sub_;
  ros::Publisher estimate_pub_, batch_pub_, pdf_pub_;
  ros::ServiceServer reset_srv_, batch_srv_;
  ros::WallTimer wait_timer_, diagnostics_timer_;
  // Registers the node again with a restarted master (own thread).
  std::unique_ptr<MasterWatch> master_watch_;
};

}  // namespace pc_ekf
