// A rule that a component's settings break, in the component's own terms:
// which setting (its key within the component's config section), its value
// and what the rule needs; an empty `setting` when none is broken. The
// component throws on it; the config parser calls the same rule and names
// the YAML key (estimator_config.cpp), so each rule is written once.
#pragma once

#include <string>

namespace pc_ekf {

struct SettingBreach {
  std::string setting, value, needs;
  bool broken() const { return !setting.empty(); }
};

}  // namespace pc_ekf
