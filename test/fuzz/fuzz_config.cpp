// Fuzz target: the YAML configuration loader (pc_ekf::parseConfigString).
// Contract: any text either parses into a config or throws pc_ekf::ConfigError
// naming the problem. Anything else -- another exception type, a crash, a
// sanitizer report, a hang, or an allocation sized by a value (the schema
// accepts up to 1e8 samples and 1e6 collocation points: parsing validates
// them, it must not allocate by them; fuzz.sh runs with -malloc_limit_mb) --
// is a bug.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "pc_ekf/io/estimator_config.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const pc_ekf::EstimatorConfig c = pc_ekf::parseConfigString(text, "fuzz.yaml");
    // An accepted config is internally consistent (what the builders rely on).
    if (c.uncertain.empty() || c.truth.xi.size() != c.uncertain.size() ||
        c.measurement.channels.empty() || c.sampling.samples < 1 ||
        !(c.sampling.duration > 0.0) || c.collocation.points < 1) {
      std::abort();
    }
  } catch (const pc_ekf::ConfigError&) {
    // the one allowed rejection
  }
  return 0;
}
