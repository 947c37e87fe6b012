#include "pc_ekf/ros/estimator_timeline.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "pc_ekf/io/estimator_config.h"
#include "pc_ekf/ros/message_conversion.h"

namespace pc_ekf {

TimelineSettings timelineSettings(const EstimatorConfig& c) {
  TimelineSettings s;
  s.road_topic_required = c.road.source == RoadSource::kTopic;
  s.road_free = c.road.source == RoadSource::kNone;
  // An analytic road is the config's own synthetic road: its origin one
  // `sampling` interval before the first sample, at once (a live node must
  // not hold back its first estimate). Road-free: the stream's own interval.
  s.analytic_interval = s.road_free ? 0.0 : c.sampling.interval();
  s.time_jump_tolerance = c.node.time_jump_tolerance;
  s.road_wait_timeout = c.node.road_wait_timeout;
  s.max_pending = static_cast<std::size_t>(c.node.max_pending_samples);
  s.max_road = static_cast<std::size_t>(c.node.max_road_samples);
  s.contacts = static_cast<int>(c.model_type->contactNames().size());
  return s;
}

const char* toString(StampVerdict v) {
  switch (v) {
    case StampVerdict::kAccepted:
      return "accepted";
    case StampVerdict::kDuplicate:
      return "duplicate_stamp";
    case StampVerdict::kOutOfOrder:
      return "out_of_order";
    case StampVerdict::kTimeJump:
      return "time_jump";
    case StampVerdict::kBeforeOrigin:
      return "before_origin";
    case StampVerdict::kNonFinite:
      return "non_finite";
    case StampVerdict::kIgnored:
      return "ignored";
  }
  return "?";
}

EstimatorTimeline::EstimatorTimeline(const TimelineSettings& settings) : settings_(settings) {
  reset();
}

void EstimatorTimeline::reset() {
  mode_ = RoadMode::kUndecided;
  origin_.reset();
  last_road_.reset();
  last_sample_.reset();
  // A new buffer, not a cleared one: the previous run's model may still hold it.
  road_ = std::make_shared<SampledRoad>(settings_.contacts);
  road_history_complete_ = true;
  last_road_arrival_ = 0.0;
  road_needed_from_ = 0.0;
  pending_.clear();
}

void EstimatorTimeline::resume(RoadMode mode, const ros::Time& origin,
                               const ros::Time& last_sample, const ContactSeries& road,
                               const std::optional<ros::Time>& last_road) {
  reset();
  mode_ = mode;
  origin_ = origin;
  last_sample_ = last_sample;
  road_history_complete_ = mode != RoadMode::kTopic;
  if (mode != RoadMode::kTopic) return;
  if (road.t.empty()) {
    last_road_ = last_road;
    return;
  }
  if (static_cast<int>(road.heights.size()) != settings_.contacts) {
    throw std::invalid_argument("the checkpoint's road has " + std::to_string(road.heights.size()) +
                                " height columns, the model " + std::to_string(settings_.contacts) +
                                " contacts");
  }
  road_ = std::make_shared<SampledRoad>(road.t, road.heights);
  last_road_ = last_road;
}

ContactSeries EstimatorTimeline::roadFrom(double t) const {
  const auto i = static_cast<std::ptrdiff_t>(road_->indexNeededFor(t));
  const auto tail = [i](const std::vector<double>& v) {
    return std::vector<double>(v.begin() + i, v.end());
  };
  ContactSeries out;
  out.t = tail(road_->times());
  for (int c = 0; c < road_->contactCount(); ++c) out.heights.push_back(tail(road_->column(c)));
  return out;
}

StampVerdict EstimatorTimeline::order(const std::optional<ros::Time>& last,
                                      const ros::Time& stamp) const {
  if (!last || stamp > *last) return StampVerdict::kAccepted;
  if (stamp == *last) return StampVerdict::kDuplicate;
  return (*last - stamp).toSec() > settings_.time_jump_tolerance ? StampVerdict::kTimeJump
                                                                 : StampVerdict::kOutOfOrder;
}

StampVerdict EstimatorTimeline::addRoad(const ros::Time& stamp, double left, double right,
                                        double arrival) {
  return addRoad(stamp, std::vector<double>{left, right}, arrival);
}

StampVerdict EstimatorTimeline::addRoad(const ros::Time& stamp, const std::vector<double>& heights,
                                        double arrival) {
  for (double h : heights) {
    if (!std::isfinite(h)) return StampVerdict::kNonFinite;
  }
  if (static_cast<int>(heights.size()) != settings_.contacts) {
    throw std::invalid_argument("EstimatorTimeline::addRoad: " + std::to_string(heights.size()) +
                                " heights for " + std::to_string(settings_.contacts) + " contacts");
  }
  if (mode_ == RoadMode::kAnalytic || settings_.road_free) return StampVerdict::kIgnored;
  const StampVerdict v = order(last_road_, stamp);
  if (v != StampVerdict::kAccepted) return v;
  if (mode_ == RoadMode::kUndecided) {
    mode_ = RoadMode::kTopic;
    origin_ = stamp;
  }
  road_->append(secondsSince(stamp, *origin_), heights);
  last_road_ = stamp;
  last_road_arrival_ = arrival;
  boundRoad();
  return StampVerdict::kAccepted;
}

void EstimatorTimeline::boundRoad() {
  if (road_->size() <= settings_.max_road) return;
  const std::size_t before = road_->size();
  road_->discardBefore(road_needed_from_);
  if (road_->size() < before) road_history_complete_ = false;
}

StampVerdict EstimatorTimeline::addSample(const ros::Time& stamp, const Measurement& m,
                                          double arrival) {
  const StampVerdict v = order(last_sample_, stamp);
  if (v != StampVerdict::kAccepted) return v;
  if (mode_ == RoadMode::kTopic && stamp < *origin_) return StampVerdict::kBeforeOrigin;
  pending_.push_back({stamp, m, arrival});
  last_sample_ = stamp;
  return StampVerdict::kAccepted;
}

std::vector<ReleasedSample> EstimatorTimeline::release(double now, DroppedSamples* dropped) {
  std::vector<ReleasedSample> out;
  while (!pending_.empty()) {
    Pending& p = pending_.front();
    const double waiting_since = std::max(p.arrival, last_road_arrival_);
    const bool expired = now - waiting_since >= settings_.road_wait_timeout ||
                         pending_.size() > settings_.max_pending;
    if (mode_ == RoadMode::kUndecided) {
      if (!expired && !settings_.road_free) break;
      if (settings_.road_topic_required) {
        ++dropped->no_road;
        pending_.pop_front();
        continue;
      }
      // t = 0 one sample interval before the first sample: the interval
      // between the first two stamps, so the first waits for the second.
      const bool observed = !(settings_.analytic_interval > 0.0);
      if (observed && pending_.size() < 2) break;
      const double interval =
          observed ? secondsSince(pending_[1].stamp, p.stamp) : settings_.analytic_interval;
      mode_ = RoadMode::kAnalytic;
      try {
        origin_ = stampAt(p.stamp, -interval);
      } catch (const std::invalid_argument&) {
        origin_ = ros::Time(0, 0);  // stamps near zero (sim time): t = stamp
      }
    }
    const double t = secondsSince(p.stamp, *origin_);
    bool held = false;
    if (mode_ == RoadMode::kTopic) {
      if (t < 0.0) {
        ++dropped->before_origin;
        pending_.pop_front();
        continue;
      }
      const bool covered = !road_->empty() && road_->lastTime() >= t;  // empty: resumed
      if (!covered && !expired) break;
      held = !covered;
    }
    ReleasedSample r{p.stamp, std::move(p.measurement), p.arrival, held};
    r.measurement.time = t;
    out.push_back(std::move(r));
    pending_.pop_front();
  }
  return out;
}

}  // namespace pc_ekf
