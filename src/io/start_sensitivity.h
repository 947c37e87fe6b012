// The sensitivity a node reports once at start (docs/real_vehicle.md): the
// record is not known yet, so the indices are a forecast over the config's
// synthetic drive, sampling.samples over sampling.duration on its analytic
// road; with a road from the topic, on the config's road.speed_bump settings,
// and said so. Road-free (road.source none) there is no road to drive and
// none is computed (truth.road describes synthetic drives, not the vehicle).
// tolerances_prune is applied only on an analytic road (the node then
// estimates what estimate_offline estimates on the same synthetic record).
#pragma once

#include <string>
#include <vector>

#include "pc_ekf/sensitivity/prior_sensitivity.h"
#include "pc_ekf/io/estimator_config.h"

namespace pc_ekf {

struct StartSensitivity {
  PriorSensitivity indices;          // empty parameters: none computed
  std::string road;                  // the road the indices are on
  std::vector<std::string> pruned;   // tolerances fixed (tolerances_prune)
  std::string note;                  // why prune was not applied, if so
};

// Computed only with tolerances (a config without them has nothing to rank
// among the vehicle values); `config` is pruned in place where allowed.
StartSensitivity startSensitivity(EstimatorConfig& config);

}  // namespace pc_ekf
