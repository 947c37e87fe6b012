#include "pc_ekf/io/start_sensitivity.h"

#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/io/record_sensitivity.h"

namespace pc_ekf {

StartSensitivity startSensitivity(EstimatorConfig& config) {
  StartSensitivity s;
  if (config.tolerance_count == 0) return s;
  if (config.road.source == RoadSource::kNone) {
    // No road known, and the live record not yet: nothing to rank over (the
    // config's truth: describes synthetic drives, not the vehicle's).
    s.note = "no start sensitivity: road.source none and the live record is not known at start; "
             "rank the tolerances with estimate_offline --sensitivity on a recorded bag";
    return s;
  }
  EstimatorConfig analytic = config;
  const bool topic = config.road.source == RoadSource::kTopic;
  if (topic) analytic.road.source = RoadSource::kSpeedBump;
  s.road = topic ? "road.speed_bump (the live road is not known at start)"
                 : toString(config.road.source);
  const std::vector<double> times =
      uniformSampleTimes(config.sampling.samples, config.sampling.duration);
  s.indices = recordSensitivity(analytic, makeModel(analytic, makeRoad(analytic)), times);
  if (config.tolerances_prune > 0.0) {
    if (topic) {
      s.note = "tolerances_prune not applied: the road comes from the topic; rank the tolerances "
               "with estimate_offline --sensitivity on a recorded bag";
    } else {
      config = pruneTolerances(config, s.indices, &s.pruned);
    }
  }
  return s;
}

}  // namespace pc_ekf
