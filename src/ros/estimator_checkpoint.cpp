#include "pc_ekf/ros/estimator_checkpoint.h"

#include <utility>
#include <vector>

namespace pc_ekf {
namespace {

using Scalar = std::uint64_t EstimatorCounters::*;
using Reasons = std::map<std::string, std::uint64_t> EstimatorCounters::*;

const std::vector<std::pair<const char*, Scalar>>& scalars() {
  static const std::vector<std::pair<const char*, Scalar>> list{
      {"samples_received", &EstimatorCounters::samples_received},
      {"samples_processed", &EstimatorCounters::samples_processed},
      {"road_received", &EstimatorCounters::road_received},
      {"road_accepted", &EstimatorCounters::road_accepted},
      {"nan_elements", &EstimatorCounters::nan_elements},
      {"road_wait_expired", &EstimatorCounters::road_wait_expired},
      {"non_finite_updates", &EstimatorCounters::non_finite_updates},
      {"batch_not_kept", &EstimatorCounters::batch_not_kept},
      {"resets", &EstimatorCounters::resets},
      {"time_jump_resets", &EstimatorCounters::time_jump_resets},
  };
  return list;
}

const std::vector<std::pair<const char*, Reasons>>& reasonMaps() {
  static const std::vector<std::pair<const char*, Reasons>> list{
      {"samples_rejected", &EstimatorCounters::samples_rejected},
      {"elements_rejected", &EstimatorCounters::elements_rejected},
      {"road_rejected", &EstimatorCounters::road_rejected},
  };
  return list;
}

}  // namespace

std::map<std::string, std::uint64_t> counterMap(const EstimatorCounters& c) {
  std::map<std::string, std::uint64_t> m;
  for (const auto& [name, field] : scalars()) m[name] = c.*field;
  for (const auto& [name, field] : reasonMaps()) {
    for (const auto& [reason, count] : c.*field) m[std::string(name) + "." + reason] = count;
  }
  return m;
}

EstimatorCounters countersFromMap(const std::map<std::string, std::uint64_t>& m,
                                  const std::string& path) {
  EstimatorCounters c;
  for (const auto& [key, count] : m) {
    bool known = false;
    for (const auto& [name, field] : scalars()) {
      if (key == name) {
        c.*field = count;
        known = true;
      }
    }
    for (const auto& [name, field] : reasonMaps()) {
      const std::string prefix = std::string(name) + ".";
      if (!known && key.size() > prefix.size() && key.rfind(prefix, 0) == 0) {
        (c.*field)[key.substr(prefix.size())] = count;
        known = true;
      }
    }
    if (!known) throw CheckpointError("checkpoint " + path + ": unknown counter '" + key + "'");
  }
  return c;
}

}  // namespace pc_ekf
