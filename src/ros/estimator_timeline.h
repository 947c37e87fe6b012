// Time base of estimator_node: the time origin, the road buffer, stamp
// ordering checks and the queue of samples waiting for road data
// (docs/method.md §8.1). No node handles: the node feeds it messages
// and wall-clock times, and takes back the samples the filter may process.
#pragma once

#include <ros/time.h>

#include <deque>
#include <memory>
#include <optional>
#include <vector>

#include "pc_ekf/filter/measurement.h"
#include "pc_ekf/io/measurement_csv.h"
#include "pc_ekf/model/road_input.h"

namespace pc_ekf {

struct EstimatorConfig;

// Where the road of the current run comes from: decided by the first message
// after start or reset.
enum class RoadMode {
  kUndecided,  // no road message yet and no sample released
  kTopic,      // road/profile; t = 0 at its first stamp
  kAnalytic,   // the config's road (or none); t = 0 one sample interval before the first sample
};

// What happened to a message offered to the timeline.
enum class StampVerdict {
  kAccepted,
  kDuplicate,     // same stamp as the previous accepted message of that stream
  kOutOfOrder,    // earlier, by at most the time-jump tolerance
  kTimeJump,      // earlier by more (looped bag, /clock reset)
  kBeforeOrigin,  // sample stamped before t = 0
  kNonFinite,     // road height NaN/Inf
  kIgnored,       // road message while the config's analytic road is in use
};
const char* toString(StampVerdict v);

struct TimelineSettings {
  bool road_topic_required = false;  // config road.source: topic
  // road.source: none: no road is used, so none is waited for: the first
  // sample sets the origin at once, and road messages are ignored.
  bool road_free = false;
  // The sample interval (s) that puts the analytic origin before the first
  // sample (an analytic road: the config's sampling interval); 0: the
  // stream's own, the interval between its first two stamps (road-free: the
  // first sample waits for the second).
  double analytic_interval = 0.0;
  double time_jump_tolerance = 0.5;  // s
  double road_wait_timeout = 0.5;    // s of wall clock
  std::size_t max_pending = 1000;
  std::size_t max_road = 1000000;
  int contacts = 2;                  // road heights per road message (the model's contacts)
};

// The settings the config's node: section gives (the origin's interval: an
// analytic road's is the config's sampling interval, road-free the stream's).
TimelineSettings timelineSettings(const EstimatorConfig& config);

// A sample the filter may process now, its time set (s since the origin).
struct ReleasedSample {
  ros::Time stamp;
  Measurement measurement;
  double arrival = 0.0;    // wall-clock seconds at arrival
  bool road_held = false;  // road data did not reach its stamp in time: held at the last value
};

// Samples given up while waiting, by reason.
struct DroppedSamples {
  int no_road = 0;        // road from the topic required, none arrived in time
  int before_origin = 0;  // stamped before the first road message
};

class EstimatorTimeline {
 public:
  explicit EstimatorTimeline(const TimelineSettings& settings);

  // Forget everything: origin re-armed, road and pending samples cleared.
  void reset();
  // Continue a checkpointed run: its road mode and origin (so stamps map to
  // the same t), samples up to `last_sample` refused as already seen. In
  // topic mode the road buffer restarts from `road` (what the filters still
  // need, roadFrom() when saved) and road messages up to `last_road` count as
  // already seen; the road history counts as incomplete (no ~estimate_batch).
  void resume(RoadMode mode, const ros::Time& origin, const ros::Time& last_sample,
              const ContactSeries& road = {}, const std::optional<ros::Time>& last_road = {});

  // `arrival`: wall-clock seconds, for the road wait of pending samples.
  StampVerdict addRoad(const ros::Time& stamp, double left, double right, double arrival);
  // Any number of contacts (settings.contacts, in the model's order).
  StampVerdict addRoad(const ros::Time& stamp, const std::vector<double>& heights, double arrival);
  // `m` without time; the channels and values are already checked.
  StampVerdict addSample(const ros::Time& stamp, const Measurement& m, double arrival);
  // Samples whose road data is there, in stamp order. A sample whose stamp
  // the road has not reached waits while road messages keep coming: it is
  // released with the road held at its last value once road_wait_timeout has
  // passed both since its arrival and since the last road message (so time
  // the node spends computing, with road messages queued, does not count),
  // or when more than max_pending samples wait. Before the run's first road
  // message the wait counts from the sample's arrival only.
  std::vector<ReleasedSample> release(double now, DroppedSamples* dropped);
  // The filters need no road before t (s since the origin): the road buffer
  // may drop older samples once it exceeds max_road.
  void keepRoadFrom(double t) { road_needed_from_ = t; }

  RoadMode mode() const { return mode_; }
  std::optional<ros::Time> origin() const { return origin_; }
  // The road of the current run when mode() is kTopic (shared with the model).
  std::shared_ptr<const SampledRoad> road() const { return road_; }
  // False once road samples were discarded to respect max_road (batch impossible).
  bool roadHistoryComplete() const { return road_history_complete_; }
  std::size_t pendingCount() const { return pending_.size(); }
  std::size_t roadCount() const { return road_->size(); }
  // The road buffer from the sample at or before t (s since the origin) on.
  ContactSeries roadFrom(double t) const;
  std::optional<ros::Time> lastRoadStamp() const { return last_road_; }

 private:
  struct Pending {
    ros::Time stamp;
    Measurement measurement;
    double arrival;
  };
  StampVerdict order(const std::optional<ros::Time>& last, const ros::Time& stamp) const;
  void boundRoad();

  TimelineSettings settings_;
  RoadMode mode_ = RoadMode::kUndecided;
  std::optional<ros::Time> origin_;
  std::optional<ros::Time> last_road_, last_sample_;
  std::shared_ptr<SampledRoad> road_;
  bool road_history_complete_ = true;
  double last_road_arrival_ = 0.0;
  double road_needed_from_ = 0.0;
  std::deque<Pending> pending_;
};

}  // namespace pc_ekf
