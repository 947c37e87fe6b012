// What a user does not know exactly about the vehicle: `tolerances:` turns
// model values known to a relative tolerance into nuisance parameters, and a
// calibration's posterior back into tolerances (docs/real_vehicle.md).
#pragma once

#include <string>
#include <vector>

#include "pc_ekf/filter/uncertain_parameters.h"
#include "pc_ekf/model/model_type.h"
#include "pc_ekf/pc/germ.h"

namespace pc_ekf {

class YamlMapReader;

// A germ map {family, alpha, beta} (absent: Beta(2, 2)).
GermSpec readGermSpec(YamlMapReader r);

// `tolerances:` of the config root: one nuisance parameter per model value
// named there, in the model's parameter order, with the model's value as
// nominal. A number is the relative half-range with a Beta(2, 2) germ; a map
// takes an `uncertain:` entry's keys (nominal, relative_range, germ). 0 (or
// relative_range 0) leaves the value fixed. A name also under `uncertain:` or
// not a model parameter is refused.
std::vector<UncertainParameter> readTolerances(YamlMapReader& root, const ModelType& type,
                                               const ModelParameters& parameters,
                                               const std::vector<UncertainParameter>& load);

// The uncertain entry of `name` in `germ` whose value nominal (1 + range xi)
// has the given mean and standard deviation (a moment-matched tolerance).
UncertainParameter momentMatched(const std::string& name, double mean, double stddev,
                                 const GermSpec& germ);

}  // namespace pc_ekf
